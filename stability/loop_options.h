// Options of the haptic loop (velocity filter, the user's hand), used by
// ZWidth; see stability/haptic_loop.h for the loop and where the hand acts.
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
