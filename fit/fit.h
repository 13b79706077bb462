// Fitting the parameters of eq. (1) (any number of sections) to a measured
// frequency response by weighted nonlinear least squares (Ceres).
//
// The residual of bin k is (H_k - G_d(e^{j theta_k}) e^{-j theta_k delay}) / s_k
// (real and imaginary parts), with G_d the exact ZOH-sampled model, not G(jw):
// at 300 Hz and 1 kHz the two differ by 18% in magnitude and 53 deg in phase.
// s_k = max(H_std_k, relative_std_floor |H_k|) is the estimator's per-bin
// standard deviation, which makes this a maximum-likelihood-like complex fit.
// Parameters live in log space: log m, log b, and per section log w,
// log zeta_c, log v, log zeta_d (c = 2 zeta_c w, d = 2 zeta_d v), with bounds.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ident/welch.h"
#include "model/plant.h"

namespace zwidth::fit {

struct FitOptions {
  int num_modes = 2;              // resonance/antiresonance sections, >= 0
  int delay_samples = 0;          // input delay [samples], >= 0, unless auto_delay
  bool auto_delay = false;        // try 0..max_auto_delay and keep the best fit
  int max_auto_delay = 4;         // >= 0
  double min_damping_ratio = 1e-4;       // lower bound of zeta_c and zeta_d, > 0
  double max_pole_damping_ratio = 0.95;  // upper bound of zeta_c, < 1 (underdamped)
  double max_zero_damping_ratio = 2.0;   // upper bound of zeta_d
  double max_frequency_fraction = 0.98;  // w, v below this fraction of Nyquist, (0, 1)
  double relative_std_floor = 1e-3;      // per-bin std floor relative to |H|, >= 0
  int max_iterations = 200;              // per start, >= 1
  double function_tolerance = 1e-8;      // Ceres relative cost change, > 0
  int max_starts = 6;                    // automatic starts tried, >= 1
  std::optional<Plant> init;             // a user's starting point (tried first)

  bool IsValid(std::string* why) const;
};

enum class FitStatus {
  kNotRun,        // sentinel
  kConverged,     // the numbers can be used
  kNoConvergence  // the solver stopped without converging: do not use the numbers
};
std::string ToString(FitStatus s);

struct FitResult {
  FitStatus status = FitStatus::kNotRun;
  std::string message;
  Plant plant;                   // canonical order: poles by omega, zeros by v
  Plant std_errors;              // same shape; +inf where unknown
  bool covariance_ok = false;
  // Full parameter covariance (scaled by std_scale), row-major (2 + 4 N)^2, in
  // the order and log space of stability/uncertainty.h: log m, log b, then per
  // section (canonical order) log omega, log c, log v, log d. Empty when the
  // covariance could not be computed.
  std::vector<double> log_covariance;
  double cost = 0.0;             // 0.5 * sum of squared weighted residuals
  int num_residuals = 0;
  int num_parameters = 0;
  double chi2_per_dof = 0.0;     // sum r^2 / (num_residuals - num_parameters)
  double nrmse_fit_percent = 0.0;  // 100 (1 - |H - G| / |H - mean H|), MATLAB compare's "fit"
  double worst_misfit_hz = 0.0;    // bin with the largest |H - G| / s
  double std_scale = 1.0;          // covariance scale: chi2/dof * bin correlation
  int starts_tried = 0;
  int iterations = 0;
  std::vector<std::string> warnings;
  std::string BriefReport() const;
};

// Throws InputError for invalid options or an unusable response (no bins,
// Nyquist unknown). A fit that does not converge returns kNoConvergence.
FitResult FitModel(const ident::FrequencyResponse& frf, const FitOptions& options);

// The automatic starting points tried by FitModel (exposed for tests).
std::vector<Plant> AutomaticStarts(const ident::FrequencyResponse& frf, int num_modes,
                                   int delay_samples, int max_starts);

// Sorts pole pairs by omega and zero pairs by v (G is unchanged); permutes
// std_errors alike when given.
void CanonicalOrder(Plant* plant, Plant* std_errors);

}  // namespace zwidth::fit
