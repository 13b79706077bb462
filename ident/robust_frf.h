// The robust method for periodic excitation (Pintelon and Schoukens, System
// Identification, 2nd ed., 2012, sec. 4.3.1; Schoukens, Pintelon and Rolain,
// Mastering System Identification in 100 Exercises, 2012, exercise 4.2): M
// random-phase multisine realisations of P >= 2 steady-state periods each.
//
// Per realisation m and excited line k, the periods' DFTs U[m,p], Y[m,p] give
// the means U_m, Y_m, their sample (co)variances over the periods divided by P
// (the noise on the means), and G_m = Y_m / U_m with its noise variance
//   var_n G_m = |G_m|^2 (var Y_m/|Y_m|^2 + var U_m/|U_m|^2 - 2 Re(cov(Y_m, U_m)/(Y_m conj U_m))).
// The best linear approximation is G = mean_m G_m; its noise variance is
// sum_m var_n G_m / M^2, its total variance the scatter over the
// realisations, sum_m |G_m - G|^2 / (M (M - 1)), and the variance due to the
// nonlinear distortions (which change with the phases, not with the period)
// the difference, total - noise (clamped at 0). With M = 1 only the noise
// variance is known (the distortion is NaN).
//
// `zwidth estimate --estimator robust --period-samples N LOG...` (each log one
// realisation; analysis/logs_estimate.h) writes H, noise_var and
// distortion_var per line, and the fit's verdict reads them
// (fit/quality.cc, reason nonlinear_distortion).
#pragma once

#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "ident/joint.h"
#include "ident/local_models.h"

namespace zwidth::ident {

struct RobustEstimate {
  std::vector<double> f_hz;               // the excited lines [Hz]
  std::vector<std::complex<double>> H;    // the best linear approximation G
  std::vector<double> noise_var;          // variance of H from the noise
  std::vector<double> distortion_var;     // variance of H from the nonlinear distortions (NaN when M = 1)
  std::vector<double> total_var;          // scatter over the realisations (NaN when M = 1)
  // One-sided PSDs of the period means, averaged over the realisations
  // [unit^2/Hz]: 2 |X_m|^2 / (fs N) for the mean DFT X_m of a period of N.
  std::vector<double> S_uu, S_yy;
  std::vector<std::complex<double>> S_uy;
  int num_periods = 0, num_realisations = 0, period_samples = 0;
  double sample_rate_hz = 0.0;
};

struct RobustOptions {
  int period_samples = 0;     // samples per period of the multisine, >= 4 (no default: the excitation's)
  int transient_periods = 1;  // whole periods dropped at the start of each record (the transient), >= 0
  double fmin_hz = 0.0;       // lines kept [Hz], >= 0
  double fmax_hz = std::numeric_limits<double>::infinity();  // > fmin_hz
  bool IsValid(std::string* why) const;  // the message names the field
};

// `realisations`: M >= 1 records (u, y; r ignored) of whole periods of
// period_samples each, in steady state (drop the transient periods first);
// the periods used are the first P = floor(length / period_samples) >= 2 of
// the shortest record. Excited lines: the period's DFT bins where the input's
// power is at least 1e-6 of its largest. Throws InputError for M = 0,
// period_samples < 4, fewer than 2 periods, u and y of different lengths, a
// rate that is not finite and > 0, or no excited line.
RobustEstimate EstimateRobust(const std::vector<LocalRecord>& realisations, double sample_rate_hz, int period_samples);

// The same after dropping options.transient_periods periods of each record,
// keeping the lines in [fmin_hz, fmax_hz]. Throws InputError for invalid
// options (naming the field) and, as above, for too few periods (saying how
// many the records hold after the transient) or no excited line in the band.
RobustEstimate EstimateRobust(const std::vector<LocalRecord>& realisations, double sample_rate_hz,
                              const RobustOptions& options);

// The estimate as the combined response the fit and the files take:
// H_std (each part) = sqrt(total_var / 2) with M >= 2 realisations (the
// best linear approximation's variance, distortions included), else
// sqrt(noise_var / 2); num_averages = effective_averages = M (M >= 2) or P;
// coherence the value that gives that std by Bendat and Piersol's formula
// (ident::CoherenceStd); bin_correlation 1 (the lines of whole periods are
// uncorrelated); noise_var copied, distortion_var too with M >= 2;
// estimator "robust".
CombinedResponse ToCombined(RobustEstimate estimate);

}  // namespace zwidth::ident
