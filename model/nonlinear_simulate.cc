#include "model/nonlinear_simulate.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Eigenvalues>

#include "model/error.h"
#include "model/state_space_internal.h"

namespace zwidth::model {
namespace {

constexpr int kMaxSwitchesPerPeriod = 64;
constexpr double kRootTolerance = 1e-13;  // of the period
constexpr int kMinCells = 2, kMaxCells = 4096;
constexpr double kCellsPerFastestPeriod = 16.0;
constexpr int kTaylorOrder = 4;   // K: the bounds use v .. v^(K) and a bound of v^(K+1)
constexpr int kMaxHalvings = 48;  // of a cell: 2^-48 of it is below the root's tolerance
// A return to v = 0 this soon after a start at v = 0 is the rounding of a
// required torque on the static level, not motion (see RunPhase).
constexpr double kImmediateReturn = 16 * kRootTolerance;  // of the period

double SpectralRadius(const Eigen::MatrixXd& A) {
  if (A.rows() == 0) return 0.0;
  return Eigen::EigenSolver<Eigen::MatrixXd>(A, false).eigenvalues().cwiseAbs().maxCoeff();
}

// psi > 0 at 0 (or 0 at a start on the boundary), "outside" at hi (psi < 0
// when strict, else <= 0), one crossing between: regula falsi (Illinois) to
// tol; returns the end of the final bracket on the outside, so that the switch
// that follows sees the new phase's condition.
template <class Psi>
double Bracket(const Psi& psi, double hi, bool strict, double tol) {
  auto outside = [&](double v) { return strict ? v < 0.0 : v <= 0.0; };
  double a = 0.0, b = hi, fa = psi(0.0), fb = psi(hi);
  int side = 0;
  for (int it = 0; it < 200 && b - a > tol; ++it) {
    double c = (a * fb - b * fa) / (fb - fa);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    const double fc = psi(c);
    if (outside(fc)) {
      b = c;
      fb = fc;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = c;
      fa = fc;
      if (side == +1) fb *= 0.5;
      side = +1;
    }
  }
  return b;
}

// sum_{k>=1} |phi^(k)(0)| h^k/k! + M h^(K+1)/(K+1)!, phi^(k)(0) = s[k] + su[k] u_p:
// phi varies by less than this over [0, h].
double Spread(const double* s, const double* su, double u_p, double M, double h) {
  double spread = 0.0, p = 1.0;
  for (int k = 1; k <= kTaylorOrder; ++k) {
    p *= h / k;
    spread += std::abs(s[k] + su[k] * u_p) * p;
  }
  return spread + M * p * h / (kTaylorOrder + 1);
}

// Bounds of phi^(j) over [0, h] from its Taylor coefficients d[0..K] at 0 and
// a bound M of |phi^(K+1)| there: d_j -+ (sum_{k>j} |d_k| h^(k-j)/(k-j)! +
// M h^(K+1-j)/(K+1-j)!). Returns +1 or -1 when phi^(j) keeps that sign, else 0.
int SignOver(const double* d, double M, int j, double h) {
  double spread = 0.0, p = 1.0;
  for (int k = j + 1; k <= kTaylorOrder; ++k) {
    p *= h / (k - j);
    spread += std::abs(d[k]) * p;
  }
  spread += M * p * h / (kTaylorOrder + 1 - j);
  return d[j] > spread ? 1 : d[j] < -spread ? -1 : 0;
}

}  // namespace

StickSlipPlant::StickSlipPlant(const StateSpace& c, const Friction& friction, double period_s)
    : x_(Eigen::VectorXd::Zero(c.A.rows())), C_(c.C), B_(c.B), period_s_(period_s), friction_(friction) {
  friction.Validate();
  if (!(std::isfinite(period_s) && period_s > 0.0)) {
    throw InputError("sample period = " + std::to_string(period_s) + " s: must be finite and > 0");
  }
  CA_ = C_ * c.A;
  CA2_ = CA_ * c.A;
  g_ = CA_.dot(B_);
  const double scale = C_.cwiseAbs().maxCoeff() * B_.cwiseAbs().maxCoeff();
  if (!(g_ > 0.0) || std::abs(C_.dot(B_)) > 1e-12 * scale || c.D != 0.0) {
    throw InputError("the stick-slip simulation needs a plant of relative degree 2 (C B = 0, C A B > 0, D = 0)");
  }
  moving_.continuous = c;
  stuck_.continuous = c;
  stuck_.continuous.A = c.A - B_ * CA2_ / g_;
  stuck_.continuous.B = Eigen::VectorXd::Zero(c.A.rows());
  const double rho = std::max(SpectralRadius(c.A), SpectralRadius(stuck_.continuous.A));
  const double cells = std::ceil(rho * period_s * kCellsPerFastestPeriod / (2.0 * std::numbers::pi));
  cell_s_ = period_s / std::clamp(cells, double(kMinCells), double(kMaxCells));
  series_.resize(kTaylorOrder + 1);
  moving_.q = CA_;
  stuck_.q = CA2_ / g_;
  for (Regime* r : {&moving_, &stuck_}) {
    const StateSpace d = DiscretizeZoh(r->continuous, cell_s_);
    r->cell_A = d.A;
    r->cell_B = d.B;
    // phi^(k)(0) = q A^(k-1) z = q A^k x + q A^(k-1) B u_p (k >= 1): rows q A^k
    // of `series` times x, plus series_u(k) u_p.
    const Eigen::MatrixXd& A = r->continuous.A;
    const Eigen::VectorXd& B = r->continuous.B;
    r->series.resize(kTaylorOrder + 1, A.rows());
    r->series_u = Eigen::VectorXd::Zero(kTaylorOrder + 1);
    Eigen::RowVectorXd row = r->q;
    for (int k = 0; k <= kTaylorOrder; ++k) {
      r->series.row(k) = row;
      if (k < kTaylorOrder) r->series_u(k + 1) = row.dot(B);
      row = row * A;
    }
    // |phi^(K+1)(t)| = |q A^K e^{At} z| <= ||q A^K S||_1 ||e^{S^-1 A S t}||_inf ||S^-1 z||_inf
    // (S the balancing scales), and ||S^-1 z||_inf <= w |x| + ||S^-1 B||_inf |u_p|
    // with w_j the largest |(S^-1 A)_ij| of column j.
    const Eigen::VectorXd sc = internal::BalancingScales(A);
    const Eigen::MatrixXd SiA = sc.cwiseInverse().asDiagonal() * A;
    const double norm = (SiA * sc.asDiagonal()).cwiseAbs().rowwise().sum().maxCoeff();
    const Eigen::RowVectorXd qAK = r->series.row(kTaylorOrder);
    r->tail = qAK.cwiseProduct(sc.transpose()).cwiseAbs().sum() * std::exp(norm * cell_s_);
    r->z_weights = SiA.cwiseAbs().colwise().maxCoeff();
    r->z_weight_u = sc.cwiseInverse().cwiseProduct(B).cwiseAbs().maxCoeff();
  }
  const StateSpace full = DiscretizeZoh(c, period_s);
  full_A_ = full.A;
  full_B_ = full.B;
  // An offset alone is a constant input: linear too.
  linear_ = friction.coulomb_pos == 0.0 && friction.coulomb_neg == 0.0 && friction.breakaway_pos == 0.0 &&
            friction.breakaway_neg == 0.0;
}

void StickSlipPlant::Reset(const Eigen::VectorXd& x) {
  x_ = x;
  const double v = CA_.dot(x_);
  phase_ = v > 0.0 ? SlipPhase::kSlidingPos : v < 0.0 ? SlipPhase::kSlidingNeg : SlipPhase::kStuck;
  fresh_start_ = false;
}

double StickSlipPlant::PlantInput(double u) const {
  switch (phase_) {
    case SlipPhase::kSlidingPos: return u + friction_.offset - friction_.coulomb_pos;
    case SlipPhase::kSlidingNeg: return u + friction_.offset + friction_.coulomb_neg;
    case SlipPhase::kStuck: break;
  }
  return 0.0;  // stuck: the holding torque is part of the stuck regime's A
}

double StickSlipPlant::Margin(const Eigen::VectorXd& x, double u) const {
  switch (phase_) {
    case SlipPhase::kSlidingPos: return CA_.dot(x);
    case SlipPhase::kSlidingNeg: return -CA_.dot(x);
    case SlipPhase::kStuck: break;
  }
  const double f_req = -(u + friction_.offset) - CA2_.dot(x) / g_;
  return std::min(f_req + friction_.StaticPos(), friction_.StaticNeg() - f_req);
}

Eigen::VectorXd StickSlipPlant::Advance(const Regime& r, const Eigen::VectorXd& x, double u_p, double t) const {
  const StateSpace d = DiscretizeZoh(r.continuous, t);
  return d.A * x + d.B * u_p;
}

void StickSlipPlant::Switch(double u) {
  x_ -= B_ * (CA_.dot(x_) / g_);
  const double f_req = -(u + friction_.offset) - CA2_.dot(x_) / g_;
  if (f_req < -friction_.StaticPos()) {
    phase_ = SlipPhase::kSlidingPos;
  } else if (f_req > friction_.StaticNeg()) {
    phase_ = SlipPhase::kSlidingNeg;
  } else {
    phase_ = SlipPhase::kStuck;
  }
  ++switches_;
  fresh_start_ = true;
  pinned_ = false;
}

double StickSlipPlant::DerivativeBound(const Regime& r, const Eigen::VectorXd& x, double u_p) const {
  return r.tail * (r.z_weights.dot(x.cwiseAbs()) + r.z_weight_u * std::abs(u_p));
}

double StickSlipPlant::Exit(const Regime& r, const Watch& w, const Eigen::VectorXd& xa, const Eigen::VectorXd& xb,
                            double u_p, double h, int depth) const {
  series_.noalias() = r.series * xa;
  double d[kTaylorOrder + 1];
  for (int k = 0; k <= kTaylorOrder; ++k) d[k] = w.sigma * (series_(k) + r.series_u(k) * u_p);
  d[0] += w.kappa;
  const double M = DerivativeBound(r, xa, u_p);
  if (SignOver(d, M, 0, h) > 0) return -1.0;  // the usual cell: far from a switch
  auto phi = [&](const Eigen::VectorXd& x) { return w.sigma * r.q.dot(x) + w.kappa; };
  auto rate = [&](const Eigen::VectorXd& x) { return w.sigma * r.q.dot(r.continuous.A * x + r.continuous.B * u_p); };
  auto at = [&](double t) { return t == 0.0 ? xa : Advance(r, xa, u_p, t); };
  auto outside = [&](double v) { return w.strict ? v < 0.0 : v <= 0.0; };
  const double tol = kRootTolerance * period_s_;
  const int s1 = SignOver(d, M, 1, h), s2 = SignOver(d, M, 2, h);
  if (outside(phi(xb))) {
    // One crossing when phi is monotone, convex or concave over the cell.
    if (s1 != 0 || s2 != 0 || depth >= kMaxHalvings) {
      return Bracket([&](double t) { return phi(at(t)); }, h, w.strict, tol);
    }
  } else {
    if (s1 != 0 || s2 < 0) return -1.0;  // monotone, or concave: its minimum is at an end
    if (s2 > 0) {                        // convex: one minimum, where phi' = 0
      if (!(d[1] < 0.0 && rate(xb) > 0.0)) return -1.0;
      const double tm = Bracket([&](double t) { return -rate(at(t)); }, h, false, tol);
      if (!outside(phi(at(tm)))) return -1.0;
      return Bracket([&](double t) { return phi(at(t)); }, tm, w.strict, tol);
    }
    if (depth >= kMaxHalvings) return -1.0;
  }
  // Neither excluded nor a single crossing: halve.
  const Eigen::VectorXd xm = Advance(r, xa, u_p, 0.5 * h);
  const double t1 = Exit(r, w, xa, xm, u_p, 0.5 * h, depth + 1);
  if (t1 >= 0.0) return t1;
  const double t2 = Exit(r, w, xm, xb, u_p, 0.5 * h, depth + 1);
  return t2 >= 0.0 ? 0.5 * h + t2 : -1.0;
}

bool StickSlipPlant::RunPhase(double u, double span, double* used) {
  const bool stuck = phase_ == SlipPhase::kStuck;
  const Regime& r = stuck ? stuck_ : moving_;
  const double u_p = PlantInput(u);
  const double s = phase_ == SlipPhase::kSlidingNeg ? -1.0 : 1.0;
  const double f = stuck ? 0.0 : PlantInput(u) - u - friction_.offset;
  // Sliding: s v. Stuck: f_req = -(u + offset) - q x inside [-StaticPos, StaticNeg],
  // one watch per side.
  const double held = u + friction_.offset;
  Watch watches[2] = {stuck ? Watch{-1.0, friction_.StaticPos() - held, true} : Watch{s, 0.0, false},
                      Watch{1.0, friction_.StaticNeg() + held, true}};
  const int num_watches = stuck ? 2 : 1;
  if (stuck && pinned_) {
    // Held on the static level (see below): the band's edge moved out to where
    // f_req is now, and a rounding beyond, so that leaving it is motion again.
    const double slack = 1e-12 * (friction_.StaticPos() + friction_.StaticNeg());
    for (Watch& w : watches) w.kappa += std::max(0.0, -(w.sigma * r.q.dot(x_) + w.kappa)) + slack;
  }
  Eigen::VectorXd xa = x_, xb;
  double ta = 0.0;
  while (span - ta > 0.0) {
    const bool whole = span - ta >= cell_s_;
    const double h = whole ? cell_s_ : span - ta;
    if (whole) {
      xb.noalias() = r.cell_A * xa;
      xb += r.cell_B * u_p;
    } else {
      xb = Advance(r, xa, u_p, h);
    }
    // The usual cell, far from a switch, is cleared here: |phi^(k)| for k >= 1
    // are the same for every watch of the phase (sigma = +-1).
    series_.noalias() = r.series * xa;
    const double spread = Spread(series_.data(), r.series_u.data(), u_p, DerivativeBound(r, xa, u_p), h);
    const double q0 = series_(0);  // Exit reuses series_
    double root = -1.0;
    for (int i = 0; i < num_watches; ++i) {
      if (watches[i].sigma * q0 + watches[i].kappa > spread) continue;
      const double t = Exit(r, watches[i], xa, xb, u_p, h, 0);
      if (t >= 0.0 && (root < 0.0 || t < root)) root = t;
    }
    if (root >= 0.0 && fresh_start_ && !stuck && root <= kImmediateReturn * period_s_) {
      // Back at v = 0 as soon as it started: the required torque sits on the
      // static level to rounding and is moving into the band. Stuck, with the
      // band's edge where f_req is (it may be outside by a rounding).
      phase_ = SlipPhase::kStuck;
      pinned_ = true;
      *used = ta;
      x_ = xa;
      return false;
    }
    fresh_start_ = false;
    if (root >= 0.0) {
      x_ = Advance(r, xa, u_p, root);
      friction_work_ += f * (C_.dot(x_) - C_.dot(xa));
      *used = ta + root;
      return false;
    }
    friction_work_ += f * (C_.dot(xb) - C_.dot(xa));
    xa.swap(xb);
    ta += h;
  }
  x_ = xa;
  *used = span;
  return true;
}

void StickSlipPlant::Step(double u) {
  if (linear_) {  // as SimulateDiscrete, operation for operation
    Eigen::VectorXd next = full_A_ * x_;
    next += full_B_ * (u + friction_.offset);
    x_.swap(next);
    return;
  }
  pinned_ = false;
  if (phase_ == SlipPhase::kStuck && Margin(x_, u) < 0.0) Switch(u);
  double t = 0.0;
  for (int n = 0;; ++n) {
    double used = 0.0;
    const bool was_pinned = pinned_;
    if (RunPhase(u, period_s_ - t, &used)) return;
    t += used;
    if (n >= kMaxSwitchesPerPeriod) {
      throw ComputationError("stick-slip simulation: more than 64 stick/slip switches in one period");
    }
    if (pinned_ && !was_pinned) continue;  // just pinned: the stuck phase starts here
    Switch(u);
  }
}

SimulatedLog SimulateNonlinearLog(const Plant& plant_in, const SimulateOptions& o, const Friction& friction,
                                  const Actuator& actuator) {
  friction.Validate();
  std::string why;
  if (!actuator.IsValid(&why)) throw InputError("actuator: " + why);
  Plant plant;
  SimulatedLog log = SimulatedTorque(plant_in, o, &plant);
  const size_t n = log.torque.size();
  StickSlipPlant device(ContinuousStateSpace(plant), friction, o.period_s());
  log.position.resize(n);
  const size_t delay = static_cast<size_t>(plant.delay_samples);
  for (size_t t = 0; t < n; ++t) {
    log.position[t] = device.position();
    device.Step(t >= delay ? actuator.Apply(log.torque[t - delay]) : actuator.Apply(0.0));
  }
  ApplySensor(o, &log.position);
  return log;
}

}  // namespace zwidth::model
