// Stress (ctest label `stress`): random models and long delays against the
// brute-force closed-loop root scan of tests/brute_force.h (the relay's are in
// relay_stress_test.cc).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "stability/zwidth.h"
#include "tests/brute_force.h"
#include "tests/test_util.h"

namespace zwidth::stability {
namespace {

// Random models: test::WideRandomModels().
model::Plant RandomModel(std::mt19937_64& rng, int nm, double T) { return test::RandomPlant(rng, test::WideRandomModels(), nm, T); }

TEST(ZWidth, StressRandomModelsAgreeWithBruteForce) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double T = 1e-3;
    const model::Plant p = RandomModel(rng, trial % 5, T);
    const int d = static_cast<int>(U(rng) * 12);
    const ZWidth z(p, T, d);
    const BruteForce bf(p, T, d);
    const double kscale = p.m / (T * T);
    for (double bfrac : {0.0, 0.3, 1.0}) {
      const double B = bfrac * p.m / T * 0.1;
      const CriticalPoint c = z.At(B);
      if (!(c.K_cr > 0) || !std::isfinite(c.K_cr)) continue;
      // Near a 0.1 rad/s mode a root moves ~1e-10 per 1e-5 of K: test at 1e-3.
      EXPECT_LT(bf.MaxRoot(c.K_cr * (1 - 1e-3), B), 1.0 + 1e-9) << trial;
      EXPECT_GE(bf.MaxRoot(c.K_cr * (1 + 1e-3), B), 1.0 - 1e-9) << trial;
      const double ref = bf.KCritical(B, 1e-6 * kscale, 1e3 * kscale);
      // The bisection reference is itself only good to ~1e-5 where a root grazes
      // the circle (|z| moves ~1e-10 per 1e-5 of K); the root check above holds.
      EXPECT_NEAR(c.K_cr, ref, 1e-4 * ref) << "trial " << trial << " d " << d << " B " << B;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

class ZWidthLongDelays : public ::testing::TestWithParam<int> {};

TEST_P(ZWidthLongDelays, LongDelaysAgreeWithBruteForce) {
  const model::Plant p = model::PhantomTable1();
  const int d = GetParam();
  const ZWidth z(p, 1e-3, d);
  const BruteForce bf(p, 1e-3, d);
  const CriticalPoint c = z.At(0.0);
  EXPECT_NEAR(c.K_cr, bf.KCritical(0.0, 1e-5, 100), 1e-6 * c.K_cr) << d;
}

INSTANTIATE_TEST_SUITE_P(Long, ZWidthLongDelays, ::testing::Values(25, 60, 100), test::DelayName());


}  // namespace
}  // namespace zwidth::stability
