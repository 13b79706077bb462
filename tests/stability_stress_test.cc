// Stress (ctest label `stress`): random models and long delays against the
// brute-force closed-loop root scan of tests/brute_force.h.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "stability/zwidth.h"
#include "tests/brute_force.h"

namespace zwidth::stability {
namespace {

TEST(ZWidth, StressRandomModelsAgreeWithBruteForce) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Plant p;
    p.m = std::pow(10.0, -5 + 5 * U(rng));
    p.b = p.m * std::pow(10.0, -1 + 2 * U(rng));
    const int nm = trial % 5;
    const double T = 1e-3;
    for (int i = 0; i < nm; ++i) {
      const double w = 2 * std::numbers::pi * (5 + 445 * U(rng));  // up to 0.45 fs
      const double v = w * (0.5 + U(rng));
      const double zc = std::pow(10.0, -3 + 2.7 * U(rng)), zd = std::pow(10.0, -3 + 2.7 * U(rng));
      p.modes.push_back({w, std::max(0.1, 2 * zc * w), std::min(v, 0.95 * std::numbers::pi / T), std::max(0.1, 2 * zd * v)});
    }
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

TEST(ZWidth, LongDelaysAgreeWithBruteForce) {
  const Plant p = PhantomTable1();
  for (int d : {25, 60, 100}) {
    const ZWidth z(p, 1e-3, d);
    const BruteForce bf(p, 1e-3, d);
    const CriticalPoint c = z.At(0.0);
    EXPECT_NEAR(c.K_cr, bf.KCritical(0.0, 1e-5, 100), 1e-6 * c.K_cr) << d;
  }
}

}  // namespace
}  // namespace zwidth::stability
