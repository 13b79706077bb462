// Options of the haptic loop as devices run it (issue 16): a velocity filter in
// the virtual wall and the user's hand on the device, used by ZWidth, the
// relay, the wall simulation and passivity (stability/passivity.h).
//
// Loop (with D = loop delay + the model's own input delay, in samples):
//
//   u = -z^-D (K + B F(z) (1 - z^-1)/T) y,    y = G_h(z) u,
//
// F(z) = (b0 + b1 z^-1 + ... + bn z^-n) / (a0 + a1 z^-1 + ... + am z^-m),
// a0 = 1, the velocity filter (F = 1: the paper's raw backward difference),
// and G_h the exact ZOH sampling of the continuous plant with the hand,
//
//   G_h(s) = G(s) / (1 + G(s) Z_h(s)),   Z_h(s) = M s^2 + B_h s + K_h.
//
// Where the hand is attached: its force acts where the motor torque does (the
// plant input) and it feels the measured coordinate y (position, velocity,
// acceleration). With modes, that treats the hand as collocated with the
// encoder and the motor: the modes stay between the torque and y exactly as
// identified, and the hand does not sit behind a compliant link. M, B_h, K_h
// are in the model's units at that coordinate (kg m^2, N m s/rad, N m/rad for
// a rotary model; kg, N s/m, N/m for a linear one).
#pragma once

#include <string>
#include <vector>

namespace zwidth::stability {

// The user's hand as a mass-damper-spring at the measured coordinate.
struct Hand {
  double M = 0.0;  // inertia added at the coordinate [kg m^2 or kg], >= 0
  double B = 0.0;  // damping [N m s/rad or N s/m], >= 0
  double K = 0.0;  // stiffness [N m/rad or N/m], >= 0
  bool IsNone() const { return M == 0.0 && B == 0.0 && K == 0.0; }
};

// The largest magnitude of a hand's M, B, K and of a filter coefficient (the
// bound of a model's parameters): beyond it the loop's polynomials overflow.
inline constexpr double kMaxLoopValue = 1e12;

struct LoopOptions {
  // Velocity filter F(z): numerator b0..bn and denominator a0..am over powers of
  // z^-1 (index i multiplies z^-i). Both empty = no filter (F = 1). Valid: a0 =
  // 1, finite, every pole strictly inside the unit circle, DC gain F(1) > 0
  // (a velocity estimate), at most 32 coefficients each.
  std::vector<double> filter_b;
  std::vector<double> filter_a;
  Hand hand;  // the user's hand; all zero = nobody holds the device
  bool HasFilter() const { return !filter_b.empty(); }
  bool IsValid(std::string* why) const;  // names the field (filter_b, filter_a, hand.M ...)
};

}  // namespace zwidth::stability
