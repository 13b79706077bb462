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
// Reads a CSV written by WriteFrequencyResponse (or any CSV with at least
// f_hz,H_re,H_im and either sample_rate_hz or --rate). Missing coherence/H_std
// columns default to 1 and |H| * 1e-3 (equal relative weights).
ident::FrequencyResponse ReadFrequencyResponseCsv(const std::string& path, double sample_rate_hz = 0.0);

// True when the file looks like a frequency-response CSV (header starts with f_hz).
bool IsFrequencyResponseFile(const std::string& path);

}  // namespace zwidth::io
