// The done-when figures of the local methods (issue 23), stress label: 16
// seeds of a 30 s Table I log (model::SimulateLog: exact ZOH, white torque
// 0.03 N m rms, 1 kHz, PHANToM encoder quantisation) fitted with two sections
// from the LRM and the LPM response, and a light-mode device (Table I with
// damping ratios 0.01). The sweep itself lives in tests/local_fit_sweep.h.
#include <gtest/gtest.h>

#include "tests/local_fit_sweep.h"

namespace zwidth {
namespace {

class LocalFitStress : public ::testing::TestWithParam<const char*> {};

// rms errors of m and b below 0.01 % and 0.05 %, the reported std within
// 0.67-1.5x of the scatter over the seeds.
TEST_P(LocalFitStress, SixteenTable1LogsMeetTheAccuracyAndStdBounds) {
  const Sweep w = MonteCarlo(model::PhantomTable1(), GetParam(), 16);
  EXPECT_LT(w.rms_m, 1e-4);
  EXPECT_LT(w.rms_b, 5e-4);
  EXPECT_GT(w.std_m / w.scatter_m, 0.67);
  EXPECT_LT(w.std_m / w.scatter_m, 1.5);
  EXPECT_GT(w.std_b / w.scatter_b, 0.67);
  EXPECT_LT(w.std_b / w.scatter_b, 1.5);
}

// Damping ratios near 0.01: the mean error of c_1 below 0.5 % with the LRM
// (the LPM's quadratic does not follow a resonance 2-3 bins wide: -0.64 %
// measured before the std floor was dropped, so only the LRM is held to it).
TEST(LocalFitStress, LightModesHaveTheirDampingUnbiasedByTheLrm) {
  const Sweep w = MonteCarlo(LightModes(), "lrm", 16);
  EXPECT_LT(std::abs(w.bias_c1), 5e-3);
  EXPECT_GT(w.std_c1 / w.scatter_c1, 0.67);
  EXPECT_LT(w.std_c1 / w.scatter_c1, 1.5);
}

INSTANTIATE_TEST_SUITE_P(Estimators, LocalFitStress, ::testing::Values("lrm", "lpm"),
                         [](const auto& info) { return std::string(info.param); });

}  // namespace
}  // namespace zwidth
