#include "stability/uncertainty.h"

#include "model/cancel.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <random>

#include <Eigen/Dense>

#include "model/c_locale.h"
#include "model/error.h"
#include "model/state_space.h"

namespace zwidth::stability {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::MatrixXd CovMatrix(const model::Plant& plant, const std::vector<double>& cov) {
  CheckLogCovariance(plant, cov);
  const int p = NumLogParameters(plant);
  return Eigen::Map<const Eigen::MatrixXd>(cov.data(), p, p);  // symmetric: order irrelevant
}

double Quad(const Eigen::VectorXd& g, const Eigen::MatrixXd& S) {
  if (!g.allFinite()) return kNaN;
  return std::sqrt(std::max(0.0, g.dot(S * g)));
}

}  // namespace

int NumLogParameters(const model::Plant& plant) { return 2 + 4 * static_cast<int>(plant.modes.size()); }

std::vector<std::string> LogParameterNames(const model::Plant& plant) {
  std::vector<std::string> n = {"m", "b"};
  for (size_t i = 0; i < plant.modes.size(); ++i) {
    for (const char* k : {"omega", "c", "v", "d"}) n.push_back("modes[" + std::to_string(i) + "]." + k);
  }
  return n;
}

model::Plant PerturbLog(const model::Plant& plant, const std::vector<double>& dx) {
  model::Plant p = plant;
  p.m *= std::exp(dx[0]);
  p.b *= std::exp(dx[1]);
  for (size_t i = 0; i < p.modes.size(); ++i) {
    p.modes[i].omega *= std::exp(dx[2 + 4 * i]);
    p.modes[i].c *= std::exp(dx[3 + 4 * i]);
    p.modes[i].v *= std::exp(dx[4 + 4 * i]);
    p.modes[i].d *= std::exp(dx[5 + 4 * i]);
  }
  return p;
}

bool UncertaintyOptions::IsValid(std::string* why) const {
  if (!(log_step > 0.0 && log_step < 0.1)) {
    if (why) *why = "UncertaintyOptions::log_step must be in (0, 0.1)";
    return false;
  }
  return true;
}

void CheckLogCovariance(const model::Plant& plant, const std::vector<double>& cov) {
  const size_t p = static_cast<size_t>(NumLogParameters(plant));
  if (cov.size() != p * p) {
    throw InputError("the parameter covariance has " + std::to_string(cov.size()) + " entries; a model with " +
                     std::to_string(plant.modes.size()) + " sections needs " + std::to_string(p * p) +
                     " ((2 + 4 N)^2)");
  }
  double scale = 0.0;
  for (double v : cov) {
    if (!std::isfinite(v)) throw InputError("the parameter covariance has a non-finite entry");
    scale = std::max(scale, std::abs(v));
  }
  for (size_t i = 0; i < p; ++i) {
    if (cov[i * p + i] > kMaxLogVariance) {
      const std::string sd = FormatG(std::sqrt(cov[i * p + i]));
      throw InputError("the parameter covariance gives log(" + LogParameterNames(plant)[i] + ") a variance of " +
                       FormatG(cov[i * p + i]) + " (a std of " + sd + " in its natural log, a factor of e^" + sd +
                       "); the covariance is of the parameters' natural logs (relative: 1e-4 is a 1 % std) and at "
                       "most " + FormatG(kMaxLogVariance) +
                       ": convert an absolute covariance C to C_ij / (x_i x_j), or drop the covariance");
    }
    for (size_t j = 0; j < i; ++j) {
      if (std::abs(cov[i * p + j] - cov[j * p + i]) > 1e-9 * scale) {
        throw InputError("the parameter covariance is not symmetric (entry " + std::to_string(i) + "," +
                         std::to_string(j) + ")");
      }
    }
  }
  const Eigen::MatrixXd S = Eigen::Map<const Eigen::MatrixXd>(cov.data(), p, p);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (S + S.transpose()));
  if (p > 0 && es.eigenvalues().minCoeff() < -1e-9 * scale) {
    throw InputError("the parameter covariance is not positive semi-definite (smallest eigenvalue " +
                     FormatG(es.eigenvalues().minCoeff()) + ")");
  }
}

PerturbedPlants SamplePerturbedPlants(const model::Plant& plant, double T, const Hand& hand, const UncertaintyOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("uncertainty options: " + why);
  PerturbedPlants r{SampledPlant(plant, T, hand), {}, {}, o.log_step};
  const int p = NumLogParameters(plant);
  for (int i = 0; i < p; ++i) {
    std::vector<double> dx(p, 0.0);
    dx[i] = o.log_step;
    r.plus.emplace_back(PerturbLog(plant, dx), T, hand);
    dx[i] = -o.log_step;
    r.minus.emplace_back(PerturbLog(plant, dx), T, hand);
  }
  return r;
}

std::vector<double> KcrStd(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                           const std::vector<CriticalPoint>& points, const UncertaintyOptions& o,
                           const LoopOptions& loop) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("uncertainty options: " + why);
  CheckLogCovariance(plant, cov);
  return KcrStd(SamplePerturbedPlants(plant, T, loop.hand, o), cov, delay, points, loop);
}

namespace {

// The crossing condition K + B V = W on z = e^{j theta} of one delay, on the
// perturbed plants: W = -z^D / G_d (by the state-space solve, as the delta
// method was validated with), V = F (1 - z^-1) / T, their theta derivatives
// (central differences, step 1e-6; V_theta exact without a filter) and W_x by
// central differences over the perturbed plants (step log_step).
class CrossingCondition {
 public:
  CrossingCondition(const PerturbedPlants& pl, int delay, const LoopOptions& loop)
      : pl_(pl), loop_(loop), T_(pl.nominal.period_s()), D_(delay + pl.nominal.plant().delay_samples) {}
  static bool AtPi(double th) { return std::abs(th - std::numbers::pi) < 1e-12; }
  std::complex<double> V(double th) const {
    const std::complex<double> zi = std::polar(1.0, -th);
    std::complex<double> F = 1.0;
    if (loop_.HasFilter()) {
      std::complex<double> nb = 0.0, na = 0.0;
      for (size_t i = loop_.filter_b.size(); i-- > 0;) nb = nb * zi + loop_.filter_b[i];
      for (size_t i = loop_.filter_a.size(); i-- > 0;) na = na * zi + loop_.filter_a[i];
      F = nb / na;
    }
    return F * (1.0 - zi) / T_;
  }
  std::complex<double> W(const SampledPlant& g, double th) const {
    return -std::polar(1.0, th * D_) / g.GdStateSpace(std::polar(1.0, th));
  }
  std::complex<double> Wth(double th) const {
    return AtPi(th) ? 0.0 : (W(pl_.nominal, th + kH) - W(pl_.nominal, th - kH)) / (2.0 * kH);
  }
  std::complex<double> Vth(double th) const {
    return !loop_.HasFilter() ? std::complex<double>(std::sin(th), std::cos(th)) / T_
                              : (AtPi(th) ? 0.0 : (V(th + kH) - V(th - kH)) / (2.0 * kH));
  }
  std::complex<double> Wx(int i, double th) const {
    return (W(pl_.plus[i], th) - W(pl_.minus[i], th)) / (2.0 * pl_.log_step);
  }
  double theta_of(double f_hz) const { return 2.0 * std::numbers::pi * f_hz * T_; }

 private:
  static constexpr double kH = 1e-6;
  const PerturbedPlants& pl_;
  const LoopOptions& loop_;
  double T_;
  int D_;
};

// How the crossing at (theta, B) moves: dK/dx at fixed B (the per-row delta
// method of uncertainty.h) and dK/dB along its branch. Off theta = pi,
// Im W(theta) = B Im V(theta) fixes theta: with den = B Im V_theta - Im W_theta,
// dtheta/dx = Im W_x / den and dtheta/dB = -Im V / den; K = Re W - B Re V.
// At theta = pi (W, V real): K = W - B V.
struct BranchSlopes {
  Eigen::VectorXd K_x;
  double K_B = kNaN;
};
BranchSlopes Branch(const CrossingCondition& cc, int p, double th, double B, bool with_K_B = true) {
  BranchSlopes s;
  s.K_x.resize(p);
  const bool at_pi = CrossingCondition::AtPi(th);
  const std::complex<double> Wth = cc.Wth(th), Vth = cc.Vth(th);
  const double den = B * Vth.imag() - Wth.imag();
  for (int i = 0; i < p; ++i) {
    const std::complex<double> Wx = cc.Wx(i, th);
    if (at_pi) { s.K_x[i] = Wx.real(); continue; }
    const double dth = Wx.imag() / den;
    s.K_x[i] = Wx.real() + (Wth.real() - B * Vth.real()) * dth;
  }
  if (!with_K_B) return s;
  const std::complex<double> V = cc.V(th);
  s.K_B = at_pi ? -V.real() : (Wth.real() - B * Vth.real()) * (-V.imag() / den) - V.real();
  return s;
}

// dB/dx of a point (theta0, B0) where the curve meets K = 0: W(theta, x) =
// B V(theta) there, two real equations in (theta, B): with a = W_theta -
// B V_theta, a dtheta - V dB = -W_x, so dB = Im(conj(a) W_x) / Im(conj(a) V).
// At theta = pi: dB = W_x / V.
Eigen::VectorXd ZeroKSlope(const CrossingCondition& cc, int p, double th, double B) {
  Eigen::VectorXd g(p);
  const std::complex<double> V = cc.V(th);
  const bool at_pi = CrossingCondition::AtPi(th);
  const std::complex<double> a = cc.Wth(th) - B * cc.Vth(th);
  for (int i = 0; i < p; ++i) {
    const std::complex<double> Wx = cc.Wx(i, th);
    g[i] = at_pi ? Wx.real() / V.real() : std::imag(std::conj(a) * Wx) / std::imag(std::conj(a) * V);
  }
  return g;
}

// The crossing at B nearest theta (nullopt when there is none within 1e-3 rad).
std::optional<Crossing> CrossingNear(const ZWidth& z, double B, double th) {
  std::optional<Crossing> best;
  for (const Crossing& c : z.Crossings(B)) {
    if (std::abs(c.theta - th) < 1e-3 && (!best || std::abs(c.theta - th) < std::abs(best->theta - th))) best = c;
  }
  return best;
}

// Two crossings on two branches that tie (the same K) at B, near theta1 and
// theta2: K_1(B, x) = K_2(B, x) moves B by dB/dx = -(K_1,x - K_2,x) /
// (K_1,B - K_2,B); upper is the branch with the larger K (either: they are
// equal there). nullopt when the crossings are not found, do not tie to
// 1e-6, or cross at the same slope.
struct Tie {
  Eigen::VectorXd B_x;
  BranchSlopes upper;
};
std::optional<Tie> TieAt(const ZWidth& z, const CrossingCondition& cc, int p, double B, double th1, double th2) {
  const std::optional<Crossing> c1 = CrossingNear(z, B, th1), c2 = CrossingNear(z, B, th2);
  if (!c1 || !c2 || c1->theta == c2->theta ||
      std::abs(c1->K - c2->K) > 1e-6 * std::max(std::abs(c1->K), std::abs(c2->K))) {
    return std::nullopt;
  }
  const BranchSlopes s1 = Branch(cc, p, c1->theta, B), s2 = Branch(cc, p, c2->theta, B);
  const double dkb = s1.K_B - s2.K_B;
  if (!std::isfinite(dkb) || !(std::abs(dkb) > 1e-12 * (std::abs(s1.K_B) + std::abs(s2.K_B)))) return std::nullopt;
  return Tie{-(s1.K_x - s2.K_x) / dkb, c1->K >= c2->K ? s1 : s2};
}

}  // namespace

std::vector<double> KcrStd(const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                           const std::vector<CriticalPoint>& points, const LoopOptions& loop) {
  const model::Plant& plant = pl.nominal.plant();
  const Eigen::MatrixXd S = CovMatrix(plant, cov);
  const int p = NumLogParameters(plant);
  const CrossingCondition cc(pl, delay, loop);
  std::vector<double> out(points.size(), kNaN);
  for (size_t k = 0; k < points.size(); ++k) {
    const CriticalPoint& c = points[k];
    if (c.K_cr == 0.0) { out[k] = 0.0; continue; }
    if (!std::isfinite(c.K_cr) || !std::isfinite(c.f_cr_hz)) continue;
    out[k] = Quad(Branch(cc, p, cc.theta_of(c.f_cr_hz), c.B, /*with_K_B=*/false).K_x, S);
  }
  return out;
}

SummaryStd SummaryStdDelta(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                           const DelaySummary& nominal, const UncertaintyOptions& o, const LoopOptions& loop) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("uncertainty options: " + why);
  CheckLogCovariance(plant, cov);
  return SummaryStdDelta(SamplePerturbedPlants(plant, T, loop.hand, o), cov, delay, nominal, loop);
}

namespace {

// The four rows d(K_CR(0), B_t, K_CR^max, B_max)/dx by central differences:
// each quantity recomputed near its nominal value (ZWidth::SummarizeNear) on
// the plants at x +- log_step e_i (2 p Z-widths).
Eigen::MatrixXd FiniteDifferenceRows(const PerturbedPlants& pl, int delay, const DelaySummary& nominal,
                                     const LoopOptions& loop) {
  const int p = NumLogParameters(pl.nominal.plant());
  const double h = pl.log_step;
  Eigen::MatrixXd J(4, p);
  for (int i = 0; i < p; ++i) {
    SummaryStd q[2];
    for (int s = 0; s < 2; ++s) q[s] = ZWidth(s == 0 ? pl.plus[i] : pl.minus[i], delay, loop).SummarizeNear(nominal);
    J(0, i) = (q[0].K_cr_at_zero_B - q[1].K_cr_at_zero_B) / (2 * h);
    J(1, i) = (q[0].B_t - q[1].B_t) / (2 * h);
    J(2, i) = (q[0].K_cr_max - q[1].K_cr_max) / (2 * h);
    J(3, i) = (q[0].B_max - q[1].B_max) / (2 * h);
  }
  return J;
}

// var = J Sigma J^T for each quantity the nominal summary has.
SummaryStd FromRows(const Eigen::MatrixXd& J, const Eigen::MatrixXd& S, const DelaySummary& nominal) {
  SummaryStd r;
  if (std::isfinite(nominal.K_cr_at_zero_B)) r.K_cr_at_zero_B = nominal.K_cr_at_zero_B == 0.0 ? 0.0 : Quad(J.row(0).transpose(), S);
  if (nominal.has_transition) r.B_t = Quad(J.row(1).transpose(), S);
  if (std::isfinite(nominal.K_cr_max)) r.K_cr_max = Quad(J.row(2).transpose(), S);
  if (std::isfinite(nominal.B_max) && nominal.B_max > 0.0) r.B_max = Quad(J.row(3).transpose(), S);
  return r;
}

// The rows of FiniteDifferenceRows by implicit differentiation on the nominal
// Z-width's crossings (O(p) evaluations of G_d, no Z-width per parameter),
// where the summary's structure is one of those below; a row left NaN is
// not one of them (the caller differences it):
// - K_CR(0): the critical crossing at B = 0 (dK/dx at fixed B).
// - B_t where two branches tie (K_1 = K_2 at B_t, K_CR continuous):
//   dB_t/dx = -(K_1,x - K_2,x) / (K_1,B - K_2,B).
// - K_CR^max at that corner: K_1,x + K_1,B dB_t/dx; at the corner where the
//   interval from 0+ closes (B_max_from_zero): K_x + K_B dB_0/dx; at a
//   smooth interior maximum (K_B = 0 there): K_x; at B = 0: K_CR(0)'s row.
// - B_max at B_max_from_zero, the curve's K = 0 point: ZeroKSlope; at a
//   reopened band's end where its interval's two ends tie: as B_t.
Eigen::MatrixXd ImplicitRows(const ZWidth& z, const PerturbedPlants& pl, int delay, const DelaySummary& nom,
                             const LoopOptions& loop) {
  const int p = NumLogParameters(pl.nominal.plant());
  const CrossingCondition cc(pl, delay, loop);
  Eigen::MatrixXd J = Eigen::MatrixXd::Constant(4, p, kNaN);
  const bool has_k0 = std::isfinite(nom.K_cr_at_zero_B) && nom.K_cr_at_zero_B != 0.0 && std::isfinite(nom.f_at_zero_B_hz);
  if (has_k0) J.row(0) = Branch(cc, p, cc.theta_of(nom.f_at_zero_B_hz), 0.0).K_x.transpose();
  // The K = 0 point at B_max_from_zero.
  std::optional<Eigen::VectorXd> b0_x;
  const double B0 = nom.B_max_from_zero;
  if (std::isfinite(B0) && B0 > 0.0) {
    std::optional<Crossing> c0;
    for (const Crossing& c : z.Crossings(B0)) if (!c0 || std::abs(c.K) < std::abs(c0->K)) c0 = c;
    const double k_scale = std::isfinite(nom.K_cr_max) ? std::abs(nom.K_cr_max) : 1.0;
    if (c0 && std::abs(c0->K) <= 1e-6 * k_scale) b0_x = ZeroKSlope(cc, p, c0->theta, B0);
  }
  // The two branches that tie at B_t.
  std::optional<BranchSlopes> winner;
  if (nom.has_transition && std::isfinite(nom.B_t)) {
    if (const std::optional<Tie> t =
            TieAt(z, cc, p, nom.B_t, cc.theta_of(nom.f_before_hz), cc.theta_of(nom.f_after_hz))) {
      J.row(1) = t->B_x.transpose();
      winner = t->upper;
    }
  }
  // K_CR^max, as SummarizeNear finds it.
  const bool at_corner = nom.has_transition && std::abs(nom.B_at_K_cr_max - nom.B_t) <= 1e-6 * nom.B_t;
  if (at_corner) {
    if (winner) J.row(2) = winner->K_x.transpose() + winner->K_B * J.row(1);
  } else if (nom.B_at_K_cr_max > 0.0) {
    const CriticalPoint cp = z.At(nom.B_at_K_cr_max);
    if (std::isfinite(cp.K_cr) && cp.K_cr > 0.0 && std::isfinite(cp.f_cr_hz)) {
      const BranchSlopes s = Branch(cc, p, cc.theta_of(cp.f_cr_hz), nom.B_at_K_cr_max);
      const bool at_zero_corner = std::isfinite(B0) && std::abs(nom.B_at_K_cr_max - B0) <= 1e-6 * B0;
      if (!at_zero_corner) J.row(2) = s.K_x.transpose();
      else if (b0_x) J.row(2) = s.K_x.transpose() + s.K_B * b0_x->transpose();
    }
  } else if (has_k0) {
    J.row(2) = J.row(0);
  }
  if (std::isfinite(nom.B_max) && nom.B_max > 0.0) {
    if (b0_x && std::abs(nom.B_max - B0) <= 1e-9 * nom.B_max) {
      J.row(3) = b0_x->transpose();
    } else if (nom.B_max > B0 * (1 + 1e-9)) {
      // A reopened band's end: its last interval closes where its two ends,
      // crossings on two branches, tie (a fold of one branch, where they
      // merge, is left to the differences).
      const std::vector<KInterval> iv = z.StableIntervals(nom.B_max * (1 - 1e-7));
      const KInterval* last = nullptr;
      for (const KInterval& v : iv) {
        if (std::isfinite(v.K_hi) && v.K_lo > 0.0 && (!last || v.K_hi - v.K_lo < last->K_hi - last->K_lo)) last = &v;
      }
      if (last && std::isfinite(last->f_lo_hz) && std::isfinite(last->f_hi_hz) &&
          std::abs(cc.theta_of(last->f_lo_hz) - cc.theta_of(last->f_hi_hz)) > 1e-2) {
        if (const std::optional<Tie> t =
                TieAt(z, cc, p, nom.B_max, cc.theta_of(last->f_lo_hz), cc.theta_of(last->f_hi_hz))) {
          J.row(3) = t->B_x.transpose();
        }
      }
    }
  }
  return J;
}

}  // namespace

SummaryStd SummaryStdDelta(const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                           const DelaySummary& nominal, const LoopOptions& loop) {
  return SummaryStdDelta(ZWidth(pl.nominal, delay, loop), pl, cov, delay, nominal);
}

SummaryStd SummaryStdImplicit(const ZWidth& z, const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                              const DelaySummary& nominal) {
  return FromRows(ImplicitRows(z, pl, delay, nominal, z.loop()), CovMatrix(pl.nominal.plant(), cov), nominal);
}

SummaryStd SummaryStdDelta(const ZWidth& z, const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                           const DelaySummary& nominal) {
  const Eigen::MatrixXd S = CovMatrix(pl.nominal.plant(), cov);
  Eigen::MatrixXd J = ImplicitRows(z, pl, delay, nominal, z.loop());
  // Which rows the summary needs and the implicit derivative did not give.
  const bool need[4] = {std::isfinite(nominal.K_cr_at_zero_B) && nominal.K_cr_at_zero_B != 0.0, nominal.has_transition,
                        std::isfinite(nominal.K_cr_max), std::isfinite(nominal.B_max) && nominal.B_max > 0.0};
  bool difference = false;
  for (int q = 0; q < 4; ++q) difference |= need[q] && !J.row(q).allFinite();
  if (difference) {
    const Eigen::MatrixXd F = FiniteDifferenceRows(pl, delay, nominal, z.loop());
    for (int q = 0; q < 4; ++q) if (!J.row(q).allFinite()) J.row(q) = F.row(q);
  }
  return FromRows(J, S, nominal);
}

SummaryStd SummaryStdFiniteDifference(const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                                      const DelaySummary& nominal, const LoopOptions& loop) {
  return FromRows(FiniteDifferenceRows(pl, delay, nominal, loop), CovMatrix(pl.nominal.plant(), cov), nominal);
}

MonteCarloResult SummaryMonteCarlo(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                                   int samples, std::uint64_t seed, const LoopOptions& loop) {
  if (samples < 2) throw InputError("SummaryMonteCarlo::samples must be >= 2");
  const Eigen::MatrixXd S = CovMatrix(plant, cov);
  const int p = NumLogParameters(plant);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  const Eigen::MatrixXd L = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  double sum[4] = {0, 0, 0, 0}, sum2[4] = {0, 0, 0, 0};
  int cnt[4] = {0, 0, 0, 0};
  for (int k = 0; k < samples; ++k) {
    PollCancel();  // model/cancel.h: a host's Ctrl-C
    Eigen::VectorXd u(p);
    for (int i = 0; i < p; ++i) u[i] = n01(rng);
    const Eigen::VectorXd dx = L * u;
    const DelaySummary s =
        ZWidth(PerturbLog(plant, std::vector<double>(dx.data(), dx.data() + p)), T, delay, loop).Summarize();
    const double v[4] = {s.K_cr_at_zero_B, s.has_transition ? s.B_t : kNaN, s.K_cr_max, s.B_max};
    for (int q = 0; q < 4; ++q) {
      if (!std::isfinite(v[q])) continue;
      sum[q] += v[q];
      sum2[q] += v[q] * v[q];
      ++cnt[q];
    }
  }
  MonteCarloResult r;
  r.samples = samples;
  double* sd[4] = {&r.std.K_cr_at_zero_B, &r.std.B_t, &r.std.K_cr_max, &r.std.B_max};
  double* mn[4] = {&r.mean.K_cr_at_zero_B, &r.mean.B_t, &r.mean.K_cr_max, &r.mean.B_max};
  for (int q = 0; q < 4; ++q) {
    if (cnt[q] < 2) continue;
    const double m = sum[q] / cnt[q];
    *mn[q] = m;
    *sd[q] = std::sqrt(std::max(0.0, (sum2[q] - cnt[q] * m * m) / (cnt[q] - 1)));
  }
  r.used_K_cr_at_zero_B = cnt[0];
  r.used_B_t = cnt[1];
  r.used_K_cr_max = cnt[2];
  r.used_B_max = cnt[3];
  return r;
}

}  // namespace zwidth::stability
