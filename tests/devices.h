// Named example devices shared by tests and benchmarks (header-only: the
// benchmarks do not link the test utility library).
#pragma once

#include "model/plant.h"

namespace zwidth::test {

// Issue 13's first example device (m 2e-3, three modes, own delay 1): its
// Z-width has reopened bands at d = 4.
inline model::Plant IssueDeviceOne() {
  model::Plant p;
  p.m = 2e-3;
  p.b = 0.008;
  p.delay_samples = 1;
  p.modes = {{439.82, 70.4, 389.56, 46.7}, {942.48, 150.8, 848.23, 101.8}, {1633.63, 261.4, 1507.96, 181.0}};
  return p;
}

}  // namespace zwidth::test
