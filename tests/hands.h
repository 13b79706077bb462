// Hands scaled to the device, shared by the tests of the haptic loop with a hand
// (hand_test.cc, closed_loop_test.cc, uncertainty_test.cc).
#pragma once

#include "model/plant.h"
#include "stability/loop_options.h"

namespace zwidth::stability {

// Hands scaled to the device (a hand on a small device is heavy for it):
// 0 none; 1 light grasp (M = 0.3 m, B = b, hand-arm resonance 2 Hz with the
// device's mass); 2 firm (M = 2 m, B = 5 b, 6 Hz).
inline Hand HandOf(int level, const model::Plant& p) {
  if (level == 0) return {};
  const double M = level == 1 ? 0.3 * p.m : 2.0 * p.m;
  const double f = level == 1 ? 2.0 : 6.0;
  const double w = 2 * M_PI * f;
  return {M, (level == 1 ? 1.0 : 5.0) * p.b, w * w * (p.m + M)};
}

}  // namespace zwidth::stability
