// Internals of the fit module, shared by its units (not installed: include
// only from fit/*.cc and the fit tests).
//   residual.cc      the weighted ZOH residual, one bounded Ceres solve, covariance
//   starts.cc        automatic starting points, grown starts for one section more
//   linear_start.cc  the Sanathanan-Koerner start
//   quality.cc       the verdict and the spurious-section tests
//   order.cc         --modes auto: the order search (BIC, stabilisation table)
//   fit.cc           options, the fixed-order fit with its delay search, FitModel
#pragma once

#include <complex>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fit/fit.h"

namespace zwidth::fit::internal {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kHz = kTwoPi;  // rad/s per Hz

// Measured data on the unit circle, prepared once per fit.
struct Bins {
  std::vector<cd> z;        // e^{j theta_k}
  std::vector<cd> delay;    // e^{-j theta_k D}
  std::vector<cd> H;
  std::vector<double> weight;  // 1 / s_k
  double period_s = 0.0;
};

// The usable bins of frf (finite, s_k = max(H_std, floor |H|) > 0), every
// `stride`-th (stride > 1 for the cheap screening of starts), for delay D.
Bins MakeBins(const ident::FrequencyResponse& frf, int delay, double floor, int stride = 1);

// The solver's log-space parameters (see fit.h) and back.
std::vector<double> ToLog(const model::Plant& p);
model::Plant FromLog(const std::vector<double>& x, int num_modes);

struct SingleFit {
  bool converged = false;
  std::vector<double> x;  // log-space parameters at the end
  double cost = std::numeric_limits<double>::infinity();
  int iterations = 0;
  std::string message;
};

// Solves from the log-space parameters xs (clamped into the box, then updated
// in place).
SingleFit Solve(const Bins& bins, int num_modes, std::vector<double>& xs, const FitOptions& o);

// (J^T J)^-1 of the weighted residual at x, row-major p x p; false when J is
// near rank deficient ((sigma_min / sigma_max)^2 < 1e-14) or not finite.
bool LogCovariance(const Bins& bins, int num_modes, const std::vector<double>& x, std::vector<double>* cov,
                   Eigen::MatrixXd* jacobian = nullptr, Eigen::VectorXd* residuals = nullptr);

// What one order's fit needs beyond FitResult: the per-bin weighted
// residuals of the final fit, for the quality tests.
struct Fixed {
  FitResult res;
  std::vector<double> f_hz;
  std::vector<cd> r;  // (H - G) / s per used bin
};

// Fits n sections to the used bins `sub` at o.delay_samples (or over the
// automatic delay search), from the automatic starts and `extra` starts.
// rescreen_poor: when the delay search's fit is poor, screen every start at
// the delays beside it too (the order search leaves it to the chosen order).
Fixed FitFixed(const ident::FrequencyResponse& sub, const FitOptions& o, int num_modes,
               const std::vector<model::Plant>& extra, bool rescreen_poor = true);

// The bins of frf where used[k] != 0, with every per-bin vector kept aligned.
ident::FrequencyResponse Restrict(const ident::FrequencyResponse& frf, const std::vector<char>& used);

// Delay [samples] that the phase of H / G_rigid across the band suggests
// (sections' excursions cancel; fit.cc); NaN when it cannot be read.
double PhaseSlopeDelay(const ident::FrequencyResponse& r);

// Starts.
model::Plant EstimateRigid(const ident::FrequencyResponse& frf, int delay);
struct Extremum { size_t index; double prominence; };
std::vector<Extremum> Peaks(const std::vector<double>& v);  // local maxima by prominence
// The automatic starting points tried by FitFixed, at most max_starts.
std::vector<model::Plant> AutomaticStarts(const ident::FrequencyResponse& frf, int num_modes, int delay_samples,
                                   int max_starts);
// Starts for n + 1 sections from an n-section fit.
std::vector<model::Plant> GrowStarts(const Fixed& prev);

// Roots of the real polynomial sum_i a[i] x^i; second-order factors (w, 2 zeta w) of roots.
std::vector<cd> Roots(const std::vector<double>& a);
std::vector<std::pair<double, double>> Quadratics(std::vector<cd> r);

// A start from a linear rational fit (Sanathanan & Koerner 1963: `iterations`
// reweighted linear least-squares passes of N(s) - s H(s) D'(s), the delay and
// the ZOH's half sample taken out), factored into eq. (1). nullopt when the
// rational fit has real poles or zeros that do not pair into n sections.
std::optional<model::Plant> LinearRationalStart(const ident::FrequencyResponse& frf, int num_modes, int delay_samples,
                                         int iterations = 6);

// Quality.
std::string Fmt(const char* fmt, double a, double b = 0, double c = 0, double d = 0);
// "a", "a or b", "a, b, or c": the non-empty items as the alternatives of one advice sentence.
std::string Alternatives(const std::vector<std::string>& items);
double Chi2Limit(const FitResult& r, const ident::FrequencyResponse& frf);  // chi2/dof above which the fit is poor
void JudgeQuality(const Fixed& fx, const ident::FrequencyResponse& sub, const FitOptions& o, FitResult* res);
// The window's leakage bound on each section's damping (a reason or a warning
// that suggests the local methods) and the robust method's distortion check.
void LeakageChecks(const ident::FrequencyResponse& sub, FitResult* res);
void DistortionCheck(const ident::FrequencyResponse& sub, FitResult* res);

// --modes auto: fits 0..o.max_modes sections to sub, fills res.order_table
// and res.order_choice, and returns the chosen order's fit.
Fixed FitOrders(const ident::FrequencyResponse& sub, const ident::ExcitedBand& band, double sample_rate_hz,
                const FitOptions& o);

}  // namespace zwidth::fit::internal
