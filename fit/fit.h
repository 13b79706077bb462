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

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ident/welch.h"
#include "model/plant.h"

namespace zwidth::fit {

struct FitOptions {
  int num_modes = 2;              // resonance/antiresonance sections, >= 0, unless auto_modes
  // Try 0..max_modes sections and keep the order with the lowest BIC among the
  // orders without a spurious section (see FitResult::order_table).
  bool auto_modes = false;
  int max_modes = 4;              // in [0, 8]
  int delay_samples = 0;          // input delay [samples], >= 0, unless auto_delay
  // Fit at the delay that the phase of H / G_rigid across the band suggests,
  // then re-solve one sample either side and on while the cost falls (fit.cc,
  // WalkDelay); keep the best fit.
  bool auto_delay = false;
  int max_auto_delay = 40;        // largest delay searched [samples], in [0, 1000]
  // Bins used: the band [fmin_hz, fmax_hz], where the input has power and the
  // coherence is usable (ident::SelectExcitedBand).
  ident::BandOptions band;
  // Responses averaging fewer Welch segments are refused (InputError): their
  // per-bin std, hence the weights, chi2 and standard errors, mean nothing.
  int min_averages = 3;                  // >= 1
  bool allow_few_averages = false;       // fit anyway; the verdict is then "poor"
  double min_damping_ratio = 1e-4;       // lower bound of zeta_c and zeta_d, > 0
  double max_pole_damping_ratio = 0.95;  // upper bound of zeta_c, < 1 (underdamped)
  double max_zero_damping_ratio = 2.0;   // upper bound of zeta_d
  double max_frequency_fraction = 0.98;  // w, v below this fraction of Nyquist, (0, 1)
  double relative_std_floor = 1e-3;      // per-bin std floor relative to |H|, >= 0
  // The floor for a response whose estimator reports its error correlation
  // (the local methods: their std includes the transient, which Welch's
  // leaves out; at 1e-3 the floor would set the weights of the bins below
  // 10 Hz of a Table I log, where the LRM's std is 1e-5..1e-3 of |H|, and
  // the std of m and b came out 2-3x their scatter). >= 0.
  double local_relative_std_floor = 0.0;
  int max_iterations = 200;              // per start, >= 1
  double function_tolerance = 1e-8;      // Ceres relative cost change, > 0
  int max_starts = 6;                    // automatic starts tried, >= 1
  // Screened starts converged fully: the best, and runners-up whose screened
  // cost is within runner_up_cost_ratio of the best's.
  int max_converged_starts = 1;          // >= 1
  double runner_up_cost_ratio = 3.0;     // >= 1
  // When the fit has a spurious section (SpuriousSections), fit one section
  // fewer, grow it back where the misfit peaks, and keep the lower cost.
  bool retry_spurious = true;
  std::optional<model::Plant> init;             // a user's starting point (tried first)

  bool IsValid(std::string* why) const;
};

// The options a user's fit starts from: the one source of the defaults of
// `zwidth fit` / `run` (FitFlags) and of Python's fit() and run(). FitOptions{}
// with the input delay searched (auto_delay): every device tried has one, and
// a fit that assumes none is poor there (chi2/dof 15.7-12283); and the order
// chosen by BIC (auto_modes): a fixed 2 sections judged a one-section device
// poor where `run` (which searched) called it good. FitOptions{} itself keeps
// a fixed delay of 0 and 2 sections for the library's own callers.
inline FitOptions UserFitOptions() {
  FitOptions o;
  o.auto_delay = true;
  o.auto_modes = true;
  return o;
}

enum class FitStatus {
  kNotRun,        // sentinel
  kConverged,     // the numbers can be used
  kNoConvergence  // the solver stopped without converging: do not use the numbers
};
std::string ToString(FitStatus s);

// Is the converged fit usable? Judged from the tests listed in FitResult.
enum class FitQuality {
  kNotJudged,  // sentinel (no converged fit)
  kGood,       // no test failed
  kPoor        // at least one test failed: see reasons; do not trust the Z-width
};
std::string ToString(FitQuality q);

struct QualityReason {
  // Machine-readable: chi2_per_dof, residual_runs, misfit_band, few_averages,
  // parameter_at_bound, spurious_section, section_outside_excited_band,
  // mode_narrower_than_bins, nonlinear_distortion,
  // order_search_at_limit,
  // delay_search_at_limit.
  std::string code;
  std::string message;  // what was seen, with the numbers
  std::string advice;   // what to try
};

// One row of the order search (the stabilisation table).
struct OrderTrial {
  int num_modes = 0;
  bool converged = false;
  double chi2_per_dof = 0.0;
  double bic = 0.0;                   // chi2 / (kappa s2) + p ln(2 N / kappa): fit.cc, Bic()
  std::vector<double> pole_hz;        // omega_i / 2 pi, ascending
  std::vector<char> persists;         // pole i within 2% of a pole of the previous order
  std::vector<std::string> spurious;  // reasons the order was rejected; empty if admissible
  int delay_samples = 0;
};

struct FitResult {
  FitStatus status = FitStatus::kNotRun;
  std::string message;
  model::Plant plant;                   // canonical order: poles by omega, zeros by v
  model::Plant std_errors;              // same shape; +inf where unknown
  bool covariance_ok = false;
  // Full parameter covariance (the sandwich of fit/bin_correlated_covariance.h:
  // the bins' correlation measured from the residuals), row-major (2 + 4 N)^2, in
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
  double std_scale = 1.0;          // chi2/dof * bin correlation: the model-based covariance's scale (diagnostic)
  int starts_tried = 0;
  int iterations = 0;
  std::vector<std::string> warnings;
  // The bins used (ident::SelectExcitedBand); band.used has one entry per bin.
  ident::ExcitedBand band;
  // Verdict: poor when any of these fails (thresholds in fit.cc, QualityTests):
  //   chi2/dof above Chi2PerDofLimit: 1.5 + 4 sqrt(2 kappa / dof) (1.0-1.4 on
  //   correct models with >= 8 averages, see the tests; scaled below 8 by
  //   Chi2SmallSampleFactor), residual runs test z < -4 on every 3rd bin
  //   (bins 3 apart are uncorrelated for Hann), one octave band with
  //   chi2/dof > 4 and > 3x the rest, fewer than min_averages segments,
  //   damping at a bound, a spurious section, a search ended at its limit.
  FitQuality quality = FitQuality::kNotJudged;
  std::vector<QualityReason> reasons;
  double runs_z = 0.0;                  // runs test statistic (min over real, imaginary parts)
  std::vector<double> misfit_band_hz;   // {lo, hi} of the flagged octave, else empty
  double band_sample_rate_hz = 0.0;     // of the response fitted
  std::string estimator;                // ident::FrequencyResponse::estimator of the response fitted
  // The robust method's median nonlinear-distortion to noise variance ratio
  // where the rigid body is set (fit/quality.cc, DistortionCheck); above 1
  // the verdict is poor (nonlinear_distortion). NaN: not known (another estimator).
  double distortion_to_noise = std::numeric_limits<double>::quiet_NaN();
  std::vector<OrderTrial> order_table;  // filled when auto_modes
  std::string order_choice;             // why this order (auto_modes)
  std::string delay_choice;             // why this delay (auto_delay)
  std::string BriefReport() const;
};

// The mean chi2/dof of a right model on `frf`, whose per-bin std is
// estimated from n averages of the same data (n = its count, 0 where the law
// is not known): Welch's H1 std (ident::CoherenceStd, n = effective_averages)
// makes a bin's |H - G|^2 / std^2 n/(n - 1) F(2, 2n - 2) distributed (the
// residual power's n - 1 complex dof, independent of the estimate's error),
// of mean n / (n - 2): 3.0 at 3 averages, 1.33 at 8, 1.18 at 13; the scatter
// of m runs about their mean (ident/joint.cc's run-scatter std, estimator
// "...-runs") F(2, 2m - 2), of mean (m - 1) / (m - 2). A response read from a
// file or a pickle (estimator unknown) takes the Welch law when it is one of
// overlapped segments (effective_averages < num_averages: what only Welch's
// overlap makes; the local and robust methods write the two equal, their
// dof), else none (a whole-record or unoverlapped file is judged as
// before). The local methods and
// the robust one have their own dof, H2 and the closed-loop estimator a law
// not derived here: none. n is capped at 2.5 (F's mean nears infinity; at n
// <= 3 F(2, 2n - 2) has no variance, so the limit's 4 sigma term is nominal).
// Measured on 16 seeded 10 s / 30 s logs of a 1-section linear stage (zwidth
// simulate, 2 kHz, the default window: 3 / 13 overlapped segments, n = 2.89 /
// 12.4): chi2/dof 2.83 / 1.16 on average, against the law's 3.24 / 1.19.
struct Chi2SmallSample {
  double n = 0.0;         // the averages the std rests on (0: no law)
  double expected = 1.0;  // a right model's mean chi2/dof, n capped at 2.5
};
inline Chi2SmallSample Chi2SmallSampleLaw(const ident::FrequencyResponse& frf) {
  const std::string& e = frf.estimator;
  const bool runs = e.size() > 5 && e.compare(e.size() - 5, 5, "-runs") == 0;
  const bool welch_h1 =
      e == "welch-h1" || (e.empty() && frf.effective_averages > 0.0 && frf.effective_averages < frf.num_averages);
  if (!runs && !welch_h1) return {};
  const double n = frf.effective_averages > 0.0 ? frf.effective_averages : frf.num_averages;
  if (!(n > 0.0)) return {};
  const double m = std::max(n, 2.5);
  return {n, runs ? (m - 1.0) / (m - 2.0) : m / (m - 2.0)};
}
// The chi2/dof limit's scale relative to a Welch response of 8 averages,
// >= 1: E_n / E_8 below 8 averages (1 at 8 or more, where Chi2PerDofLimit's
// 1.5 was set, and where no law is known).
inline double Chi2SmallSampleFactor(const ident::FrequencyResponse& frf) {
  const Chi2SmallSample law = Chi2SmallSampleLaw(frf);
  return law.n > 0.0 ? std::max(1.0, law.expected / (8.0 / 6.0)) : 1.0;
}

// chi2/dof above which a model does not explain a response `frf` within its
// per-bin std, for `dof` degrees of freedom: 1.5 (on correct models with >= 8
// averages chi2/dof is 1.0-1.4, the per-bin std being estimated from the same
// averages) plus 4 standard deviations of chi2/dof for correlated bins,
// 4 sqrt(2 kappa / dof) (kappa: frf.bin_correlation), times
// Chi2SmallSampleFactor(frf) below 8 averages. The fit's verdict, its order
// search and `validate` all use it.
inline double Chi2PerDofLimit(int dof, const ident::FrequencyResponse& frf) {
  const double base = 1.5 + 4.0 * std::sqrt(2.0 * std::max(1.0, frf.bin_correlation) / std::max(1, dof));
  return base * Chi2SmallSampleFactor(frf);
}

// Throws InputError for invalid options or an unusable response (no bins,
// Nyquist unknown). A fit that does not converge returns kNoConvergence.
FitResult FitModel(const ident::FrequencyResponse& frf, const FitOptions& options);

// Reasons the fitted sections may be spurious: a pole that its nearest zero
// cancels (|N/D - 1| < 0.05 at s = j omega, or < 0.5 with the two frequencies
// within 2 % and within two std of each other), a damping ratio at its bound, a
// std larger than the value, a section outside the used band. Sections are
// named as printed: canonical order, from 1.
std::vector<std::string> SpuriousSections(const FitResult& r, const FitOptions& o);

// Sorts pole pairs by omega and zero pairs by v (G is unchanged); permutes
// std_errors alike when given.
void CanonicalOrder(model::Plant* plant, model::Plant* std_errors);

}  // namespace zwidth::fit
