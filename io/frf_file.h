// Frequency-response files written by `zwidth estimate` and read by `zwidth fit`.
// CSV: header f_hz,H_re,H_im,coherence,H_std,H_mag,H_phase_deg,S_uu,S_yy,
//      sample_rate_hz,num_averages,effective_averages,bin_correlation
//      (the last four are constant columns, so any CSV reader gets them).
// HDF5: datasets of the same names under /frf, scalars as root attributes.
#pragma once

#include <string>

#include "ident/welch.h"

namespace zwidth::io {

void WriteFrequencyResponse(const std::string& path, const ident::FrequencyResponse& frf);
// Reads what WriteFrequencyResponse writes, CSV or HDF5 by the file's content
// (any CSV with at least f_hz,H_re,H_im will do, and an HDF5 file with those
// under /frf), with the sample rate from the file or sample_rate_hz > 0 (which
// wins). Missing coherence/H_std default to 1 and |H| * 1e-3 (equal relative
// weights). HDF5 is parsed in a child process (io/isolated.h).
ident::FrequencyResponse ReadFrequencyResponse(const std::string& path, double sample_rate_hz = 0.0);

// True for a frequency-response file: a CSV whose header starts with f_hz, or
// an HDF5 file with a /frf group.
bool IsFrequencyResponseFile(const std::string& path);

}  // namespace zwidth::io
