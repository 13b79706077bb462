// Issue 31's hardest corner the model format accepts: 64 sections 1 % apart
// at damping ratio 1e-4 (omega_i = 300 x 1.01^i rad/s, v_i = 0.93 omega_i,
// Table I's m and b, T = 1 ms), at delays 0, 2 and 20. Its poles are so
// ill-conditioned (eigenvalue_shift 3.4e-4) that the closed loop's double
// eigenvalues misjudge points 1e-5 (relative, in K) from K_CR(0), and long
// double ones cannot resolve the integrator's root 6e-14 inside the circle
// at K ~ 1e-13; the referee is the 30-digit brute force of
// tests/brute_force_wide.h (its own realisation and a Taylor ZOH), every
// point of the grid decided by it.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "model/plant.h"
#include "stability/zwidth.h"
#include "tests/brute_force_wide.h"

namespace zwidth::stability {
namespace {

class ZWidthCorner : public ::testing::TestWithParam<int> {};

TEST_P(ZWidthCorner, KcrAndAKBGridAgreeWithTheThirtyDigitBruteForce) {
#if ZWIDTH_HAVE_WIDE_BRUTE_FORCE
  const int d = GetParam();
  const double T = 1e-3;
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < 64; ++i) {
    const double w = 300.0 * std::pow(1.01, i), v = 0.93 * w;
    p.modes.push_back({w, 2e-4 * w, v, 2e-4 * v});
  }
  const ZWidth z(p, T, d);
  ASSERT_FALSE(z.uses_polynomial_test());
  const DelaySummary s = z.Summarize();
  EXPECT_FALSE(s.conditioning_warning.empty()) << "the summary warns that the answer rests on the crossings";
  const WideBruteForce wide(p, d, T);

  // K_CR(0) within 1e-6 of the 30-digit bisection (7 steps over 1 -+ 1e-5:
  // to 1.6e-7), verified, and every caller's one test right 1e-6 from it.
  const CriticalPoint c = z.At(0.0);
  ASSERT_GT(c.K_cr, 0.0);
  ASSERT_TRUE(std::isfinite(c.K_cr));
  EXPECT_TRUE(c.verified);
  const double k_wide = WideBisect(wide, c.K_cr, 0.0, 1e-5, 7);
  std::printf("d = %d: K_CR(0) = %.12g, 30-digit brute force %.12g (relative %.3g); B_max %.6g\n", d, c.K_cr, k_wide,
              c.K_cr / k_wide - 1.0, s.B_max);
  EXPECT_NEAR(c.K_cr / k_wide, 1.0, 1e-6);
  for (double r : {1e-6, 1e-5}) {
    EXPECT_TRUE(z.IsStable(c.K_cr * (1 - r), 0.0)) << r;
    EXPECT_FALSE(z.IsStable(c.K_cr * (1 + r), 0.0)) << r;
    EXPECT_LT(wide.MaxRootMinusOne(c.K_cr * (1 - r), 0.0), 0.0) << r;
    EXPECT_GE(wide.MaxRootMinusOne(c.K_cr * (1 + r), 0.0), 0.0) << r;
  }

  // The (K, B) grid of tests/brute_force.h's Classify up to 1.1 B_max, each
  // point decided by the 30-digit eigenvalues (1 + (|z| - 1) keeps a root
  // 1e-15 inside the circle below 1 in double).
  ClassifyGrid g;
  g.b_top = std::isfinite(s.B_max) && s.B_max > 0 ? 1.1 * s.B_max : 1e-12;
  g.num_b = 3;
  g.min_points = 24;
  g.points_inside = 2;
  const Tally t = Classify(z, [&](double K, double B) { return 1.0 + wide.MaxRootMinusOne(K, B); }, p, T, d, g);
  std::printf("d = %d: %ld points, %ld stable, %ld near a boundary, %ld disagree\n", d, t.points, t.stable,
              t.near_boundary, t.disagree);
  EXPECT_EQ(t.disagree, 0);
  EXPECT_GT(t.stable, 0);
  EXPECT_LT(t.stable, t.points);
#else
  GTEST_SKIP() << "Boost.Multiprecision not found: no 30-digit brute force";
#endif
}

INSTANTIATE_TEST_SUITE_P(SixtyFourSectionsOnePercentDamping1e4, ZWidthCorner, ::testing::Values(0, 2, 20),
                         [](const ::testing::TestParamInfo<int>& i) { return "delay_" + std::to_string(i.param); });

}  // namespace
}  // namespace zwidth::stability
