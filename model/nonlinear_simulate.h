// The device of eq. (1) with its nonlinear parts (issue 32): Coulomb friction
// at the plant input (model::Friction), the actuator's DAC step and saturation
// (model::Actuator), the encoder step and sensor noise, simulated exactly.
//
// Method. The input is held over each period (ZOH). The motor and the encoder
// are collocated and the plant has relative degree 2 (C B = 0, g = C A B > 0),
// so the motor velocity is v = C A x and its acceleration C A^2 x + g u_p.
//   - Sliding (v != 0, one direction s): the friction is the constant torque
//     -coulomb_pos (s > 0) or +coulomb_neg (s < 0), so the plant sees the held
//     input u_p = u + offset + f and the exact ZOH transition applies. v(t) is
//     then an explicit function of time, C A (e^{At} x + int_0^t e^{As} ds B u_p),
//     walked in cells no longer than 1/16 of the fastest period of A. A cell
//     is cleared of any zero of s v by a bound, not by its ends alone: with
//     z = x'(0) = A x + B u_p, the derivatives are v^(k)(0) = C A^k z, and
//     |v^(K+1)(t)| <= ||C A^(K+1) S||_1 e^{||S^-1 A S||_inf h} ||S^-1 z||_inf
//     (S the balancing scales), so the Taylor polynomial of order K = 4 with
//     that remainder bounds v, v' and v'' over the cell from above and below.
//     No zero if s v's lower bound is > 0; one zero, found by regula falsi, if
//     the end is outside and v' or v'' keeps its sign; none if both ends are
//     inside and v' keeps its sign or s v is concave; if s v is convex, its
//     one minimum (the zero of v') is checked. Otherwise the cell is halved
//     (the midpoint state by the exact transition) and each half decided the
//     same way: a reversal and return inside a cell, however short, is found
//     (only a touch of zero to the rounding of the bounds could be missed).
//     Roots by regula falsi (Illinois) on the exact solution, to 1e-13 of the
//     period.
//   - At v = 0 the torque the friction must supply to hold the body is
//     f_req = -(u + offset) - C A^2 x / g (it makes the acceleration zero). If
//     -breakaway_pos <= f_req <= breakaway_neg the body sticks, else it slides
//     in the direction the net torque pushes it.
//   - Stuck: the friction is f_req(t), which makes the plant input
//     u_p = -C A^2 x / g: a linear autonomous system x' = (A - B C A^2 / g) x
//     (the constrained system, as the hand feedback of stability/hand.cc),
//     exactly sampled the same way. C A x stays 0 and the position stays put;
//     flexible sections (modes) keep moving. The body breaks away when f_req(t)
//     leaves the static band: again a crossing of an explicit function of time,
//     C A^2 e^{A_s t} x / g, with each side of the band bounded as v is above.
// Each phase is the exact solution of its linear system, and each switch is at
// the root of an exact function of time, so the simulation is exact to the
// rounding of the matrix exponentials and the root's tolerance: no sign() in a
// fixed-step integrator, no chattering about v = 0. At a switch the velocity
// left by the root's tolerance is removed along B (x -= B (C A x)/g, which
// keeps the position since C B = 0). A start at v = 0 that is back at 0 within
// 16 root tolerances is the required torque on the static level to rounding:
// the body is held stuck, the band's edge moved to where f_req is, so that it
// breaks away again when f_req leaves (tests/stick_slip_reference_test.cc
// checks all of this against a brute force that shares none of it).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "model/friction.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"

namespace zwidth::model {

enum class SlipPhase { kStuck, kSlidingPos, kSlidingNeg };

// One continuous plant with Coulomb friction at its input, advanced one
// period at a time. Starts at rest (x = 0).
class StickSlipPlant {
 public:
  // `continuous`: D = 0, C B = 0 and C A B > 0 (ContinuousStateSpace(plant), or
  // with the hand: stability::ContinuousStateSpaceWithHand). Throws InputError
  // for an invalid friction, a period that is not finite and > 0, or a
  // realisation without relative degree 2.
  StickSlipPlant(const StateSpace& continuous, const Friction& friction, double period_s);

  // One period with the plant input (after the actuator and any delay) held at u.
  // Throws ComputationError when a period needs more than 64 switches.
  void Step(double u);

  // Restarts from state x: stuck when C A x = 0, else sliding with its sign.
  void Reset(const Eigen::VectorXd& x);

  double position() const { return C_.dot(x_); }
  double velocity() const { return CA_.dot(x_); }
  SlipPhase phase() const { return phase_; }
  const Eigen::VectorXd& state() const { return x_; }
  // Stick/slip/reversal switches so far.
  int64_t switches() const { return switches_; }
  // Work done by the Coulomb friction so far [J]: f times the distance slid in
  // each sliding phase (friction is constant there; stuck, the body does not
  // move). <= 0 without an offset.
  double friction_work() const { return friction_work_; }

 private:
  struct Regime {
    StateSpace continuous;      // moving: (A, B); stuck: (A - B C A^2 / g, 0)
    Eigen::MatrixXd cell_A;     // its exact transition over one grid cell
    Eigen::VectorXd cell_B;
    // The watched function q x (moving: v = C A x; stuck: C A^2 x / g, the part
    // of f_req that moves) and its derivatives at a state x under the held u_p:
    // the k-th is series.row(k) x + series_u(k) u_p (row k = q A^k).
    Eigen::RowVectorXd q;
    Eigen::MatrixXd series;
    Eigen::VectorXd series_u;
    // A bound of the (K+1)-th derivative over a cell: tail (w |x| + w_u |u_p|).
    double tail = 0.0;
    Eigen::RowVectorXd z_weights;
    double z_weight_u = 0.0;
  };
  // A watched function of the state, phi(x) = sigma q x + kappa: sliding s v
  // (sigma = s, kappa = 0); stuck, the distance of f_req to one side of the band.
  struct Watch {
    double sigma = 1.0, kappa = 0.0;
    bool strict = false;  // outside when < 0 (stuck) rather than <= 0 (sliding)
  };
  // > 0 while the current phase goes on: s v sliding, the distance of f_req
  // inside the static band stuck.
  double Margin(const Eigen::VectorXd& x, double u) const;
  double PlantInput(double u) const;  // u_p of the current phase (0 stuck: it is in A)
  Eigen::VectorXd Advance(const Regime& r, const Eigen::VectorXd& x, double u_p, double t) const;
  // Advances up to `span` in the current phase.
  // true: reached `span`; false: a switch at *used (x_ holds the state there).
  bool RunPhase(double u, double span, double* used);
  // The first t in (0, h] where phi leaves its inside on the exact path from
  // xa (inside) to xb (at h), or -1 when it stays inside: bounds, else halving.
  // A bound of |phi^(K+1)| over a cell from x under u_p (see Regime).
  double DerivativeBound(const Regime& r, const Eigen::VectorXd& x, double u_p) const;
  double Exit(const Regime& r, const Watch& w, const Eigen::VectorXd& xa, const Eigen::VectorXd& xb, double u_p,
              double h, int depth) const;
  void Switch(double u);  // at v = 0 or a breakaway: choose stuck / sliding, remove the residual v

  Eigen::VectorXd x_;
  mutable Eigen::VectorXd series_;  // scratch of Exit
  Eigen::MatrixXd full_A_;  // the moving regime over one period (the linear path)
  Eigen::VectorXd full_B_;
  bool linear_ = false;     // no Coulomb level: one exact ZOH step per period
  bool pinned_ = false;     // stuck since a start on the static level (see RunPhase)
  Eigen::RowVectorXd C_, CA_, CA2_;
  Eigen::VectorXd B_;
  double g_ = 0.0, period_s_ = 0.0, cell_s_ = 0.0;
  Friction friction_;
  Regime moving_, stuck_;
  SlipPhase phase_ = SlipPhase::kStuck;
  bool fresh_start_ = false;  // the phase began at v = 0 and has not yet advanced
  int64_t switches_ = 0;
  double friction_work_ = 0.0;
};

// SimulateLog (model/simulate.h) on the nonlinear device: the same torque
// (logged as commanded, before the actuator), the actuator's DAC step and
// saturation, the input delay, the friction, then the encoder step and the
// sensor noise. With zero friction and no actuator limits it is SimulateLog
// itself, sample for sample. Throws InputError for invalid options, model,
// friction or actuator.
SimulatedLog SimulateNonlinearLog(const Plant& plant, const SimulateOptions& options, const Friction& friction,
                                  const Actuator& actuator);

}  // namespace zwidth::model
