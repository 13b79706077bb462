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
//     then an explicit function of time, C A (e^{At} x + int_0^t e^{As} ds B u_p);
//     its first zero in the period is bracketed on a grid of cells no longer
//     than 1/16 of the fastest period of A (so v changes sign at most once per
//     cell; a cell whose ends have the sliding sign but whose acceleration turns
//     is searched for a touch of zero too) and found by regula falsi (Illinois)
//     on the exact solution, to 1e-13 of the period.
//   - At v = 0 the torque the friction must supply to hold the body is
//     f_req = -(u + offset) - C A^2 x / g (it makes the acceleration zero). If
//     -breakaway_pos <= f_req <= breakaway_neg the body sticks, else it slides
//     in the direction the net torque pushes it.
//   - Stuck: the friction is f_req(t), which makes the plant input
//     u_p = -C A^2 x / g: a linear autonomous system x' = (A - B C A^2 / g) x
//     (the constrained system, as the hand feedback of stability/haptic_loop.cc),
//     exactly sampled the same way. C A x stays 0 and the position stays put;
//     flexible sections (modes) keep moving. The body breaks away when f_req(t)
//     leaves the static band: again a crossing of an explicit function of time.
// Each phase is the exact solution of its linear system, and each switch is at
// the root of an exact function of time, so the simulation is exact to the
// rounding of the matrix exponentials and the root's tolerance: no sign() in a
// fixed-step integrator, no chattering about v = 0. At a switch the velocity
// left by the root's tolerance is removed along B (x -= B (C A x)/g, which
// keeps the position since C B = 0).
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
  };
  // > 0 while the current phase goes on: s v sliding, the distance of f_req
  // inside the static band stuck.
  double Margin(const Eigen::VectorXd& x, double u) const;
  double Acceleration(const Eigen::VectorXd& x, double u_p) const;
  double PlantInput(double u) const;  // u_p of the current phase (0 stuck: it is in A)
  Eigen::VectorXd Advance(const Regime& r, const Eigen::VectorXd& x, double u_p, double t) const;
  // Advances up to `span` in the current phase.
  // true: reached `span`; false: a switch at *used (x_ holds the state there).
  bool RunPhase(double u, double span, double* used);
  double FindRoot(const Regime& r, const Eigen::VectorXd& x0, double u, double u_p, double lo, double hi,
                  bool on_acceleration) const;
  void Switch(double u);  // at v = 0 or a breakaway: choose stuck / sliding, remove the residual v

  Eigen::VectorXd x_;
  Eigen::MatrixXd full_A_;  // the moving regime over one period (the linear path)
  Eigen::VectorXd full_B_;
  bool linear_ = false;     // no Coulomb level: one exact ZOH step per period
  bool pinned_ = false;     // stuck for the rest of this period (see RunPhase)
  Eigen::RowVectorXd C_, CA_, CA2_;
  Eigen::VectorXd B_;
  double g_ = 0.0, period_s_ = 0.0, cell_s_ = 0.0;
  Friction friction_;
  Regime moving_, stuck_;
  SlipPhase phase_ = SlipPhase::kStuck;
  bool fresh_start_ = false;  // the phase began at v = 0 in this cell walk
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
