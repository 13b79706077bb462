// Uncertainty of the Z-width from the fitted parameters' covariance.
//
// Parameters: x = (log m, log b, then per section i: log omega_i, log c_i,
// log v_i, log d_i), the natural logs of the SI values of eq. (1) (so their
// covariance is in relative units: sqrt(cov_ii) is the relative std). The
// covariance is (2 + 4 N)^2 numbers, row-major, in that order.
//
// Delta method, two ways:
// - K_CR(B) at a fixed B, by implicit differentiation of the crossing
//   condition 1 + z^-D (K + B (1 - z^-1)/T) G_d(z; x) = 0 at z = e^{j theta}:
//   with W = -z^D / G_d, Im: (B/T) sin theta = Im W fixes theta(x), and
//   K = Re W - (B/T)(1 - cos theta), so
//     dtheta/dx = Im W_x / ((B/T) cos theta - Im W_theta),
//     dK/dx = Re W_x + (Re W_theta - (B/T) sin theta) dtheta/dx
//   (theta = pi: dK/dx = Re W_x). It holds where K_CR is set by one simple
//   crossing: not where two crossings tie (at B_t), not at a fold of B(theta)
//   (the denominator vanishes), not where K_CR = 0 (std 0 there: the loop is
//   unstable at K = 0+ for every nearby parameter) or +inf (nan).
//   W_x by central differences of G_d in x (step log_step), W_theta by central
//   differences in theta.
// - K_CR(0), B_t, K_CR^max and B_max: the derivative of each quantity, then
//   var = J Sigma J^T. By implicit differentiation on the nominal crossings
//   where the summary's structure is known (K_CR(0) and a smooth maximum as
//   above; B_t where two branches tie: dB_t/dx = -(K_1,x - K_2,x) /
//   (K_1,B - K_2,B); K_CR^max at a corner through dB_t/dx or dB_0/dx; B_max
//   at the curve's K = 0 point B_0: W = B V there, so with a = W_theta -
//   B V_theta, dB_0/dx = Im(conj(a) W_x) / Im(conj(a) V); at a reopened band's
//   end where its interval's two ends tie, as B_t): O(p) evaluations of
//   G_d. Elsewhere each quantity is recomputed near its nominal value
//   (ZWidth::SummarizeNear) for x +- log_step e_i (2 p Z-widths). Valid where
//   the quantity is a smooth function of x (not where, e.g., B_max jumps
//   between two bands).
// With a velocity filter and a hand (LoopOptions, stability/loop_options.h) the
// same holds with V = F (1 - z^-1)/T in place of (1 - z^-1)/T: B Im V = Im W
// fixes theta, dtheta/dx = Im W_x / (B Im V_theta - Im W_theta),
// dK/dx = Re W_x + (Re W_theta - B Re V_theta) dtheta/dx; the hand stays fixed.
// Monte Carlo samples x ~ N(x0, Sigma) (seeded) and recomputes Summarize().
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/plant.h"
#include "stability/zwidth.h"

namespace zwidth::stability {

// 2 + 4 * number of sections.
int NumLogParameters(const model::Plant& plant);
// Names in the order above: "m", "b", "modes[0].omega", ...
std::vector<std::string> LogParameterNames(const model::Plant& plant);
// The plant with every parameter multiplied by exp(dx_i).
model::Plant PerturbLog(const model::Plant& plant, const std::vector<double>& dx);

struct UncertaintyOptions {
  double log_step = 1e-4;  // central-difference step in log parameters, in (0, 0.1)
  bool IsValid(std::string* why) const;
};

// The largest variance of a parameter's natural log that the delta method and
// Monte Carlo take: a std of 10 (a factor e^10 = 2.2e4 at one std). Past it
// the parameter is unknown, the linearisation means nothing, and Monte Carlo
// draws plants at factors e^{+-40} and beyond (exp over- and underflows by
// 1e300, and a variance of 1e4 took over 120 s for 20 samples): such a matrix
// is almost always an absolute covariance given where a relative one belongs.
inline constexpr double kMaxLogVariance = 100.0;

// Throws InputError when the covariance is not (2 + 4 N)^2 finite numbers, not
// symmetric positive semi-definite (to 1e-9 relative), or has a diagonal entry
// above kMaxLogVariance (naming the parameter).
void CheckLogCovariance(const model::Plant& plant, const std::vector<double>& log_covariance);

// The sampled plant at x0 and at x0 +- log_step e_i for every log parameter,
// built once per (plant, period, hand) and shared by every delay.
struct PerturbedPlants {
  SampledPlant nominal;
  std::vector<SampledPlant> plus, minus;  // [i]: at x0 + log_step e_i, x0 - log_step e_i
  double log_step = 1e-4;
};
// Throws InputError for invalid options, plant, period or hand.
PerturbedPlants SamplePerturbedPlants(const model::Plant& plant, double period_s, const Hand& hand = {},
                                      const UncertaintyOptions& options = {});

// The two estimates below on shared perturbed plants (loop.hand must be
// plants.nominal.hand()); the same numbers as the overloads that sample.
std::vector<double> KcrStd(const PerturbedPlants& plants, const std::vector<double>& log_covariance,
                           int delay_samples, const std::vector<CriticalPoint>& points,
                           const LoopOptions& loop = {});
SummaryStd SummaryStdDelta(const PerturbedPlants& plants, const std::vector<double>& log_covariance,
                           int delay_samples, const DelaySummary& nominal, const LoopOptions& loop = {});
// The same on the nominal Z-width z of that delay (z.loop() the loop), when
// the caller has it (else one is built).
SummaryStd SummaryStdDelta(const ZWidth& z, const PerturbedPlants& plants, const std::vector<double>& log_covariance,
                           int delay_samples, const DelaySummary& nominal);
// The implicit derivatives alone: nan where the summary's structure is not
// one they cover (SummaryStdDelta then differences).
SummaryStd SummaryStdImplicit(const ZWidth& z, const PerturbedPlants& plants, const std::vector<double>& log_covariance,
                              int delay_samples, const DelaySummary& nominal);
// Every row by central differences of the re-evaluated quantities
// (ZWidth::SummarizeNear on 2 p perturbed Z-widths): the reference the
// implicit derivatives are checked against, and their fallback.
SummaryStd SummaryStdFiniteDifference(const PerturbedPlants& plants, const std::vector<double>& log_covariance,
                                      int delay_samples, const DelaySummary& nominal, const LoopOptions& loop = {});

// Std of K_CR at each point (points from ZWidth::At on the same plant, T, delay).
std::vector<double> KcrStd(const model::Plant& plant, const std::vector<double>& log_covariance,
                           double period_s, int delay_samples,
                           const std::vector<CriticalPoint>& points,
                           const UncertaintyOptions& options = {}, const LoopOptions& loop = {});

// Std of K_CR(0), B_t, K_CR^max, B_max by the delta method (see above).
SummaryStd SummaryStdDelta(const model::Plant& plant, const std::vector<double>& log_covariance,
                           double period_s, int delay_samples, const DelaySummary& nominal,
                           const UncertaintyOptions& options = {}, const LoopOptions& loop = {});

struct MonteCarloResult {
  int samples = 0;   // drawn
  SummaryStd std;    // sample std of each quantity over the samples where it is finite
  SummaryStd mean;   // sample mean, likewise
  int used_K_cr_at_zero_B = 0, used_B_t = 0, used_K_cr_max = 0, used_B_max = 0;  // finite samples
};
// Throws InputError for samples < 2.
MonteCarloResult SummaryMonteCarlo(const model::Plant& plant, const std::vector<double>& log_covariance,
                                   double period_s, int delay_samples, int samples, std::uint64_t seed,
                                   const LoopOptions& loop = {});

}  // namespace zwidth::stability
