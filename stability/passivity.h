// The passivity boundary of the haptic loop (stability/loop_options.h) beside
// its stability boundary (stability/zwidth.h).
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "stability/loop_options.h"

namespace zwidth::stability {

// ---- Passivity (Colgate and Schenkel, 1997, Theorem 1, in their notation):
// the sampled system of a mass m with physical damping b, ZOH, and a discrete
// environment H(z) is passive iff
//   b > (T/2) / (1 - cos(w T)) Re{(1 - e^{-j w T}) H(e^{j w T})},  0 <= w <= pi/T.
// With H = z^-D (K + B F(z)(1 - z^-1)/T) and theta = w T this is, exactly,
//   b > K P(theta) - B R(theta),
//   P = (T/2) sin((2D + 1) theta/2) / sin(theta/2),  R = Re{e^{-j(D+1) theta} F(e^{j theta})}
// (P(0) = (2D + 1) T/2). For D = 0, F = 1: b > K T/2 + |B|. It is affine in K at
// fixed B, so the passive K >= 0 form an interval [K_lo, K_hi] with
//   K_hi = min over P > 0 of (b + B R)/P,   K_lo = max(0, max over P < 0 of (b + B R)/P).
// b is the rigid body's damping of the model (the modes and the hand are not
// part of the condition: it is the device-side physical damping of the theorem).
struct PassivityOptions {
  int min_grid_points = 4096;     // uniform theta grid on [0, pi], >= 64
  int grid_points_per_delay = 64; // extra points per sample of delay (+ filter order), >= 8
  double theta_tolerance = 1e-12; // Brent refinement of each local minimum [rad], in (0, 1e-3)
  bool IsValid(std::string* why) const;
};

struct PassiveInterval {
  // Largest passive K at this B [N m/rad]; 0 when no K >= 0 is passive.
  double K_hi = std::numeric_limits<double>::quiet_NaN();
  double K_lo = 0.0;  // smallest passive K >= 0 [N m/rad]
  double theta_hi = std::numeric_limits<double>::quiet_NaN();  // where K_hi is set [rad/sample]
  bool passive_set_empty = false;
};

class Passivity {
 public:
  // b_phys: the physical damping [N m s/rad] (> 0); total_delay D >= 0.
  Passivity(double b_phys, double period_s, int total_delay, const LoopOptions& loop,
            const PassivityOptions& options = {});
  PassiveInterval At(double B) const;
  // At(B).K_hi alone: the lower bounds are searched only for one at or above
  // K_hi (which empties the set), not for the largest.
  double KHi(double B) const;
  // The condition's right-hand side K P - B R at theta (for tests and plots).
  double Rhs(double K, double B, double theta) const;

 private:
  void PR(double theta, double* P, double* R) const;
  // min over theta of sign (b + B R)/P where sign P > 0, if below `best`
  // (else `best`); *theta (may be null): where it is set.
  double Smallest(double B, double sign, double best, double* theta) const;
  double b_, T_;
  int D_;
  LoopOptions loop_;
  PassivityOptions options_;
  // The theta grid, P, R and 1/P (0 where P = 0) on it; penalties added to the
  // upper bounds (0 where P > 0, +inf elsewhere) and to minus the lower ones
  // (0 where P < 0, +inf elsewhere); the grid points where P = 0.
  std::vector<double> th_, P_, R_, inv_P_, upper_penalty_, lower_penalty_;
  std::vector<size_t> zero_P_;
  // Bounds of the lines a_i + s_i B over a block's points of one sign of P,
  // and of the steps between neighbours (see the constructor).
  struct LineBounds {
    bool any = false;
    bool edge = false;  // a point here has a neighbour of the other sign (or P = 0)
    double a_min = std::numeric_limits<double>::infinity(), a_max = -std::numeric_limits<double>::infinity();
    double s_min = std::numeric_limits<double>::infinity(), s_max = -std::numeric_limits<double>::infinity();
    double a_abs = 0.0, s_abs = 0.0, da_max = 0.0, ds_max = 0.0;
  };
  struct Block {
    size_t first = 0, last = 0;  // grid points [first, last)
    LineBounds up, down;         // where P > 0, where P < 0
  };
  std::vector<Block> blocks_;
};

}  // namespace zwidth::stability
