#include "model/nonlinear_simulate.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Eigenvalues>

#include "model/error.h"

namespace zwidth::model {
namespace {

constexpr int kMaxSwitchesPerPeriod = 64;
constexpr double kRootTolerance = 1e-13;  // of the period
constexpr int kMinCells = 2, kMaxCells = 4096;
constexpr double kCellsPerFastestPeriod = 16.0;

double SpectralRadius(const Eigen::MatrixXd& A) {
  if (A.rows() == 0) return 0.0;
  return Eigen::EigenSolver<Eigen::MatrixXd>(A, false).eigenvalues().cwiseAbs().maxCoeff();
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
  for (Regime* r : {&moving_, &stuck_}) {
    const StateSpace d = DiscretizeZoh(r->continuous, cell_s_);
    r->cell_A = d.A;
    r->cell_B = d.B;
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
  if (pinned_) return 1.0;
  const double f_req = -(u + friction_.offset) - CA2_.dot(x) / g_;
  return std::min(f_req + friction_.StaticPos(), friction_.StaticNeg() - f_req);
}

double StickSlipPlant::Acceleration(const Eigen::VectorXd& x, double u_p) const {
  return CA2_.dot(x) + g_ * u_p;
}

Eigen::VectorXd StickSlipPlant::Advance(const Regime& r, const Eigen::VectorXd& x, double u_p, double t) const {
  const StateSpace d = DiscretizeZoh(r.continuous, t);
  return d.A * x + d.B * u_p;
}

// psi > 0 at lo, psi "outside" at hi; returns the end of the final bracket on
// the outside, so that the switch that follows sees the new phase's condition.
double StickSlipPlant::FindRoot(const Regime& r, const Eigen::VectorXd& x0, double u, double u_p, double lo,
                                double hi, bool on_acceleration) const {
  const double s = phase_ == SlipPhase::kSlidingNeg ? -1.0 : 1.0;
  const bool strict = phase_ == SlipPhase::kStuck && !on_acceleration;
  auto psi = [&](double t) {
    const Eigen::VectorXd x = t == 0.0 ? x0 : Advance(r, x0, u_p, t);
    return on_acceleration ? -s * Acceleration(x, u_p) : Margin(x, u);
  };
  auto outside = [&](double v) { return strict ? v < 0.0 : v <= 0.0; };
  double a = lo, b = hi, fa = psi(lo), fb = psi(hi);
  int side = 0;
  for (int it = 0; it < 200 && b - a > kRootTolerance * period_s_; ++it) {
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
}

bool StickSlipPlant::RunPhase(double u, double span, double* used) {
  const bool stuck = phase_ == SlipPhase::kStuck;
  const Regime& r = stuck ? stuck_ : moving_;
  const double u_p = PlantInput(u);
  const double s = phase_ == SlipPhase::kSlidingNeg ? -1.0 : 1.0;
  const double f = stuck ? 0.0 : PlantInput(u) - u - friction_.offset;
  Eigen::VectorXd xa = x_, xb;
  double ta = 0.0;
  while (span - ta > 0.0) {
    const bool whole = span - ta >= cell_s_;
    const double h = whole ? cell_s_ : span - ta;
    xb = whole ? Eigen::VectorXd(r.cell_A * xa + r.cell_B * u_p) : Advance(r, xa, u_p, h);
    const double mb = Margin(xb, u);
    double root = -1.0;
    if (stuck ? mb < 0.0 : mb <= 0.0) {
      if (fresh_start_ && !stuck) {  // the required torque sits on the static level to rounding
        phase_ = SlipPhase::kStuck;
        pinned_ = true;
        *used = ta;
        x_ = xa;
        return false;
      }
      root = FindRoot(r, xa, u, u_p, 0.0, h, false);
    } else if (!stuck && s * Acceleration(xa, u_p) < 0.0 && s * Acceleration(xb, u_p) > 0.0) {
      // v has a minimum inside the cell: does it touch zero there?
      const double tm = FindRoot(r, xa, u, u_p, 0.0, h, true);
      if (Margin(Advance(r, xa, u_p, tm), u) <= 0.0) root = FindRoot(r, xa, u, u_p, 0.0, tm, false);
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
    if (RunPhase(u, period_s_ - t, &used)) return;
    t += used;
    if (n >= kMaxSwitchesPerPeriod) {
      throw ComputationError("stick-slip simulation: more than 64 stick/slip switches in one period");
    }
    if (!pinned_) Switch(u);
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
