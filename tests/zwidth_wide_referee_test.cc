// Issue 31: K_CR(0) of 32 lightly damped sections 1 % apart (damping ratio
// 1e-4, d = 2; the closed loop's order is 69) against the 30-digit brute
// force of tests/brute_force_wide.h, where the long double one errs by 1.6e-6
// (BM_CrowdedModeBoundary/32).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "model/plant.h"
#include "stability/zwidth.h"
#include "tests/brute_force_wide.h"

namespace zwidth::stability {
namespace {

TEST(ZWidthWideReferee, ThirtyTwoCrowdedSectionsKcrIsTheWideBruteForces) {
#if ZWIDTH_HAVE_WIDE_BRUTE_FORCE
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < 32; ++i) {
    const double w = 300.0 * std::pow(1.01, i), v = 0.93 * w;
    p.modes.push_back({w, 2e-4 * w, v, 2e-4 * v});
  }
  const double T = 1e-3;
  const ZWidth z(p, T, 2);
  const CriticalPoint c = z.At(0.0);
  ASSERT_GT(c.K_cr, 0.0);
  ASSERT_TRUE(std::isfinite(c.K_cr));
  // The boundary lies within 1e-9 (relative) of K_CR: stable just below,
  // unstable just above, in 30 digits (the critical root moves by ~4e-14 in
  // |z| there, 1e16 times the 30-digit eigenvalues' error).
  const WideBruteForce wide(p, 2, T);
  const double below = wide.MaxRootMinusOne(c.K_cr * (1 - 1e-9), 0.0);
  const double above = wide.MaxRootMinusOne(c.K_cr * (1 + 1e-9), 0.0);
  std::printf("K_CR(0) = %.15g; 30-digit brute force: |z| - 1 = %.3g at K_CR (1 - 1e-9), %.3g at K_CR (1 + 1e-9)\n",
              c.K_cr, below, above);
  EXPECT_LT(below, 0.0);
  EXPECT_GE(above, 0.0);
#else
  GTEST_SKIP() << "Boost.Multiprecision not found: no 30-digit brute force";
#endif
}

}  // namespace
}  // namespace zwidth::stability
