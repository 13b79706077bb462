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
// Status: computation only (issue 23 item 2, first part); not yet in the
// estimate's output columns or the fit's verdict.
#pragma once

#include <complex>
#include <vector>

#include "ident/local_models.h"

namespace zwidth::ident {

struct RobustEstimate {
  std::vector<double> f_hz;               // the excited lines [Hz]
  std::vector<std::complex<double>> H;    // the best linear approximation G
  std::vector<double> noise_var;          // variance of H from the noise
  std::vector<double> distortion_var;     // variance of H from the nonlinear distortions (NaN when M = 1)
  std::vector<double> total_var;          // scatter over the realisations (NaN when M = 1)
  int num_periods = 0, num_realisations = 0;
};

// `realisations`: M >= 1 records (u, y; r ignored) of whole periods of
// period_samples each, in steady state (drop the transient periods first);
// the periods used are the first P = floor(length / period_samples) >= 2 of
// the shortest record. Excited lines: the period's DFT bins where the input's
// power is at least 1e-6 of its largest. Throws InputError for M = 0,
// period_samples < 4, fewer than 2 periods, u and y of different lengths, a
// rate that is not finite and > 0, or no excited line.
RobustEstimate EstimateRobust(const std::vector<LocalRecord>& realisations, double sample_rate_hz, int period_samples);

}  // namespace zwidth::ident
