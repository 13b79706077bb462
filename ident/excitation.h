// Input signals to excite a rig (the role of MATLAB's idinput and
// frest.Sinestream): band-limited noise, a Schroeder-phase multisine with a
// whole number of periods, and a logarithmic chirp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace zwidth::ident {

enum class ExcitationKind {
  kNoise,      // Gaussian, made periodic-band-limited: DFT bins outside [fmin, fmax] zeroed
  kMultisine,  // equal-amplitude lines k f0 in [fmin, fmax], Schroeder (1970) phases
  kChirp,      // f(t) = fmin (fmax / fmin)^(t / T), constant amplitude
};
std::string ToString(ExcitationKind k);
bool FromString(const std::string& s, ExcitationKind* k);

struct ExcitationOptions {
  ExcitationKind kind = ExcitationKind::kMultisine;
  double seconds = 30.0;          // requested length [s], > 0 (a multisine keeps whole periods)
  double sample_rate_hz = 1000.0; // [Hz], > 0
  double rms = 0.03;              // RMS of the signal [input unit, e.g. N m], > 0
  double fmin_hz = 0.5;           // band [Hz]: >= 0 (chirp: > 0); multisine: also its line spacing f0
  double fmax_hz = 100.0;         // (fmin, Nyquist)
  uint64_t seed = 1;              // noise, and a multisine's random phases
  // Multisine: phases uniform in [0, 2 pi) drawn from `seed` instead of
  // Schroeder's: one random-phase realisation per seed, what the robust method
  // (ident/robust_frf.h) needs M >= 2 of to tell nonlinear distortion from noise.
  bool random_phases = false;
  bool IsValid(std::string* why) const;
};

struct Excitation {
  double sample_rate_hz = 0.0;
  std::vector<double> signal;
  double rms = 0.0;                  // measured [input unit]
  double crest_factor = 0.0;         // max |x| / rms
  double band_power_fraction = 0.0;  // periodogram power in [fmin, fmax] / total
  int period_samples = 0;            // multisine: one period; otherwise the length
  int num_periods = 1;
  int num_lines = 0;                 // multisine: excited harmonics of f0
  double line_spacing_hz = 0.0;      // multisine: f0
};

// Throws InputError for invalid options (naming the field) and for a band
// with no multisine line in it.
Excitation MakeExcitation(const ExcitationOptions& options);

// max |x| / rms(x), and the fraction of sum |X_k|^2 (one-sided DFT of the
// whole signal) in [fmin, fmax]: what MakeExcitation reports.
double CrestFactor(const std::vector<double>& x);
double BandPowerFraction(const std::vector<double>& x, double sample_rate_hz, double fmin_hz, double fmax_hz);

}  // namespace zwidth::ident
