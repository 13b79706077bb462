// A model checked on a log it was not fitted to, as MATLAB users do with
// compare(data, sys) and resid(data, sys):
//   - time domain: the model's simulated output for the log's input (exact
//     ZOH, the model's delay), with the initial state and a constant input
//     offset estimated by least squares (as compare estimates initial
//     conditions: an encoder's zero, the body's initial motion and a torque
//     bias are not in the model), MATLAB's fit % (NRMSE), and the residual's
//     autocorrelation and cross-correlation with the input against the
//     99 % bounds +-2.576 / sqrt(N) (resid);
//   - frequency domain: the fresh log's Welch response against the model in
//     the bins the fit's band rule keeps (ident::SelectExcitedBand), in units
//     of the per-bin std: chi2/dof with dof = 2 x bins (nothing is fitted),
//     judged by the fit's own limit fit::Chi2PerDofLimit, 1.5 + 4 sqrt(2 kappa /
//     dof), scaled below 8 Welch averages (fit::Chi2SmallSampleFactor).
// The verdict is poor when the response misfit exceeds that limit (the
// calibrated test: a right model gives chi2/dof ~ 1 at many averages, about
// n / (n - 2) at n, fit::Chi2SmallSampleLaw) or when the simulation
// explains less than the output's mean (fit % < 0). The residual tests are
// reported beside, with a warning when more lags than 5 % fall outside the
// 99 % bounds: with tens of thousands of samples they flag model errors far
// below what changes a Z-width, so they do not decide the verdict.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ident/welch.h"
#include "io/log.h"
#include "io/model_json.h"

namespace zwidth::analysis {

struct ValidateOptions {
  ident::WelchOptions welch;   // the fresh log's response (the estimate's defaults)
  ident::BandOptions band;     // the bins compared (the fit's defaults)
  double relative_std_floor = 1e-3;  // per-bin std floor relative to |H|, as the fit's
  int max_lag = 50;            // correlation lags [samples], in [1, 10000]
  int min_averages = 3;        // fewer Welch segments are refused (no usable std)
  bool IsValid(std::string* why) const;
};

struct ValidationResult {
  // Time domain.
  double fit_percent = 0.0;             // 100 (1 - |y - y_sim| / |y - mean(y)|)
  std::vector<double> simulated;        // y_sim per sample [rad]
  double input_offset = 0.0;            // estimated constant input offset [N m]
  std::vector<double> residual_autocorrelation;  // lags 0..max_lag, r_ee(k) / r_ee(0)
  std::vector<double> cross_correlation;         // lags -max_lag..max_lag, r_eu(k) / sqrt(r_ee(0) r_uu(0))
  double correlation_bound = 0.0;       // 2.576 / sqrt(N)
  int autocorrelation_outside = 0;      // lags 1..max_lag beyond the bound
  int cross_correlation_outside = 0;    // lags -max_lag..max_lag beyond the bound
  // Frequency domain.
  ident::FrequencyResponse response;    // the fresh log's
  ident::ExcitedBand band;
  double chi2_per_dof = 0.0;
  int dof = 0;
  double chi2_limit = 0.0;
  std::vector<double> normalised_misfit;  // |H - G| / std per bin (nan where unused)
  // Verdict.
  bool good = false;
  std::vector<std::string> reason_codes;  // "response_misfit", "simulation_worse_than_mean"
  std::vector<std::string> reasons;       // the same in words
  std::vector<std::string> warnings;      // "residual_correlated_with_input", ...
};

// Throws InputError for invalid options, a log of another rate than the
// model's sample_period_s, or a log too short for min_averages segments.
ValidationResult Validate(const io::ModelFile& model, const io::Log& log, const ValidateOptions& options = {});

// The result as `zwidth validate -o` writes it: the verdict first, the figures,
// the correlations; without the per-sample and per-bin vectors.
nlohmann::ordered_json ValidationToJson(const ValidationResult& r);

// One line per sample: t, u, y, y_sim, e = y - y_sim (MATLAB compare's plot).
std::string ValidationTraceCsv(const io::Log& log, const ValidationResult& r);

}  // namespace zwidth::analysis
