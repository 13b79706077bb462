// A brute-force reference for the stick-slip simulation (model/nonlinear_simulate.h),
// written without its method: the plant x' = A x + B (u + offset + f) is
// integrated by classical RK4 in fixed substeps of T / substeps, with the
// friction f chosen plainly at every substep:
//   sliding with v = C A x of sign s: f = -coulomb_pos (s > 0) or +coulomb_neg;
//   stuck: f is the torque that keeps the acceleration zero,
//     f_req = -(u + offset) - C A^2 x / g (g = C A B), so the RK4 right-hand
//     side is A x - B C A^2 x / g, evaluated as it is written;
// and the switches located by bisection inside the substep where they happen:
//   sliding, the substep's end has s v <= 0: bisect on the fraction of the
//     substep (each trial an RK4 step of that length from the substep's start)
//     for the velocity's zero; there the velocity is set to zero along B and
//     the phase chosen from f_req: stuck inside [-breakaway_pos, breakaway_neg],
//     else sliding the way the net torque pushes;
//   stuck, f_req at the substep's end is outside the static band: bisect for
//     the breakaway, then slide.
// A reversal and return inside one substep is missed, so the substep must be
// far below any time scale of the plant (T / 1000 at 1 kHz: 1 us). Shared by
// tests/stick_slip_reference_test.cc and bench/friction_sim_benchmark.cc.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "model/friction.h"
#include "model/state_space.h"

namespace zwidth::testing {

class StickSlipReference {
 public:
  StickSlipReference(const model::StateSpace& c, const model::Friction& f, double period_s, int substeps)
      : A_(c.A), B_(c.B), C_(c.C), f_(f), h_(period_s / substeps), substeps_(substeps) {
    CA_ = C_ * A_;
    CA2_ = CA_ * A_;
    g_ = CA_.dot(B_);
    x_ = Eigen::VectorXd::Zero(A_.rows());
  }

  // One period with the input held at u.
  void Step(double u) {
    u_ = u;
    if (s_ == 0) {  // a new held input may break the body away
      Decide();
      switches_ += s_ != 0;
    }
    for (int k = 0; k < substeps_; ++k) Substep();
  }

  // Restarts from state x: sliding with the sign of C A x, stuck at 0.
  void Reset(const Eigen::VectorXd& x) {
    x_ = x;
    const double v = CA_.dot(x_);
    s_ = v > 0.0 ? 1 : v < 0.0 ? -1 : 0;
  }

  double position() const { return C_.dot(x_); }
  double velocity() const { return CA_.dot(x_); }
  int64_t switches() const { return switches_; }

 private:
  double Freq(const Eigen::VectorXd& x) const { return -(u_ + f_.offset) - CA2_.dot(x) / g_; }
  double SlidingForce(int s) const { return s > 0 ? -f_.coulomb_pos : f_.coulomb_neg; }
  Eigen::VectorXd Rate(const Eigen::VectorXd& x) const {
    if (s_ == 0) return A_ * x - B_ * (CA2_.dot(x) / g_);
    return A_ * x + B_ * (u_ + f_.offset + SlidingForce(s_));
  }
  Eigen::VectorXd Rk4(const Eigen::VectorXd& x, double h) const {
    const Eigen::VectorXd k1 = Rate(x);
    const Eigen::VectorXd k2 = Rate(x + 0.5 * h * k1);
    const Eigen::VectorXd k3 = Rate(x + 0.5 * h * k2);
    const Eigen::VectorXd k4 = Rate(x + h * k3);
    return x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  // > 0 while the present phase holds.
  double Holds(const Eigen::VectorXd& x) const {
    if (s_ != 0) return s_ * CA_.dot(x);
    const double fr = Freq(x);
    return std::min(fr + f_.StaticPos(), f_.StaticNeg() - fr);
  }
  // At v = 0: stuck, or sliding the way the net torque pushes.
  void Decide() {
    x_ -= B_ * (CA_.dot(x_) / g_);
    const double fr = Freq(x_);
    s_ = fr < -f_.StaticPos() ? 1 : fr > f_.StaticNeg() ? -1 : 0;
  }
  void Substep() {
    double left = h_;
    for (int guard = 0; left > 0.0 && guard < 16; ++guard) {
      const Eigen::VectorXd end = Rk4(x_, left);
      if (s_ == 0 ? Holds(end) >= 0.0 : Holds(end) > 0.0) {
        x_ = end;
        return;
      }
      double lo = 0.0, hi = left;  // Holds > 0 (or >= 0 stuck) at lo, not at hi
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        const double m = Holds(Rk4(x_, mid));
        if (s_ == 0 ? m >= 0.0 : m > 0.0) {
          lo = mid;
        } else {
          hi = mid;
        }
      }
      x_ = Rk4(x_, hi);
      left -= hi;
      const int before = s_;
      if (s_ == 0) {  // breakaway: slide the way f_req left the band
        s_ = Freq(x_) < 0.0 ? 1 : -1;
      } else {
        Decide();
      }
      switches_ += s_ != before;
    }
  }

  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
  Eigen::RowVectorXd C_, CA_, CA2_;
  model::Friction f_;
  double g_ = 0.0, h_ = 0.0, u_ = 0.0;
  int substeps_ = 1;
  int s_ = 0;  // 0 stuck, +1 / -1 sliding
  Eigen::VectorXd x_;
  int64_t switches_ = 0;
};

// Positions at the start of each period of the input u.
inline std::vector<double> StickSlipReferenceLog(const model::StateSpace& c, const model::Friction& f,
                                                 const std::vector<double>& u, double period_s, int substeps) {
  StickSlipReference r(c, f, period_s, substeps);
  std::vector<double> y(u.size());
  for (size_t k = 0; k < u.size(); ++k) {
    y[k] = r.position();
    r.Step(u[k]);
  }
  return y;
}

}  // namespace zwidth::testing
