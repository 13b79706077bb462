// Internals of io/frf_file.cc for the fuzzer (tests/fuzz). Not installed.
#pragma once

#include <string>

#include "ident/welch.h"

namespace zwidth::io::internal {

// ReadFrequencyResponse without the child process for HDF5 (the fuzzer's
// entry point; the isolation is tested on its own).
ident::FrequencyResponse ReadFrequencyResponseInProcess(const std::string& path, double sample_rate_hz = 0.0);

}  // namespace zwidth::io::internal
