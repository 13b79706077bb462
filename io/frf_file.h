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
// Also a response made elsewhere: a CSV whose header names f (or f_hz), H_re,
// H_im and optionally coherence (coh), H_std (std), num_averages (n_avg),
// sample_rate_hz (fs); a .mat file (v5/v7 or v7.3) with f and H (complex) and
// the same optional variables (io/frf_mat.cc). Without H_std, the std is
// derived from the coherence and the number of averages (Bendat & Piersol:
// |H| sqrt((1 - coh) / (2 n coh)), ident::CoherenceStd), an InputError when
// the averages are not given; `note` (may be null) then says so.
ident::FrequencyResponse ReadFrequencyResponse(const std::string& path, double sample_rate_hz = 0.0);
ident::FrequencyResponse ReadFrequencyResponse(const std::string& path, double sample_rate_hz, std::string* note);

// True for a frequency-response file: a CSV whose header starts with f_hz (or
// f and names H_re), an HDF5 file with a /frf group, or a .mat file with f
// and H (or H_re) variables.
bool IsFrequencyResponseFile(const std::string& path);

// Throws InputError naming `source`, the first bin and the value when any
// value of r is NaN or infinite; the cause when it can tell (spectra that
// overflowed: an input scaled out of range; an infinite per-bin std).
// WriteFrequencyResponse calls it: a non-finite response is never written.
// The rules a response file's reader applies to the whole response (sizes
// agree, every value finite, f_hz >= 0 increasing and below Nyquist, coherence
// in [0, 1], H_std > 0, num_averages >= 1): InputError naming `source` and the
// column. For a response made in memory (the Python FrequencyResponse).
void CheckResponseValues(const ident::FrequencyResponse& r, const std::string& source);

void CheckFiniteResponse(const ident::FrequencyResponse& r, const std::string& source);

// Throws InputError naming `source`, the band and the flag to limit it when
// some bins have no input power: S_uu <= kNoInputPower x its peak (an
// excitation with no content there, e.g. a band-limited multisine in a
// rectangular segment, where H is 0/0 or rounding noise).
inline constexpr double kNoInputPower = 1e-24;
void CheckInputPower(const ident::FrequencyResponse& r, const std::string& source);

}  // namespace zwidth::io
