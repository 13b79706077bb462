// stability/zwidth.h: the Z-width of the paper (eq. 2), its boundary, its stable
// intervals and its B-grid, against the paper's appendix, closed forms and the
// brute force of tests/brute_force.h.
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/state_space.h"
#include "stability/loop_options.h"
#include "stability/velocity_filter.h"
#include "stability/zwidth.h"
#include "tests/brute_force.h"
#include "tests/devices.h"
#include "tests/test_util.h"

namespace zwidth::stability {
namespace {

TEST(ZWidth, AppendixModelFactsAtTwoAndFourSamples) {
  const model::Plant p = model::PhantomTable1();
  const DelaySummary s2 = ZWidth(p, 1e-3, 2).Summarize();
  EXPECT_NEAR(s2.B_t, 0.0855, 0.0005);
  EXPECT_NEAR(s2.K_cr_max, 36.74, 0.01);
  EXPECT_NEAR(s2.f_before_hz, 27.8, 0.1);
  EXPECT_NEAR(s2.f_after_hz, 171, 1);
  EXPECT_NEAR(s2.B_max_from_zero, 0.0997, 0.0001);
  EXPECT_NEAR(s2.B_max, 0.0997, 0.0001);  // no reopened band here
  EXPECT_TRUE(s2.reopened_bands.empty());
  const DelaySummary s4 = ZWidth(p, 1e-3, 4).Summarize();
  EXPECT_NEAR(s4.B_t, 0.2262, 0.0005);
  EXPECT_NEAR(s4.K_cr_max, 35.24, 0.01);
  EXPECT_NEAR(s4.f_before_hz, 33.1, 0.1);
  EXPECT_NEAR(s4.f_after_hz, 259.5, 0.5);
}

TEST(ZWidth, RigidBodyAtTwoSamples) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  const CriticalPoint c = ZWidth(p, 1e-3, 2).At(0.0);
  const BruteForce bf(p, 1e-3, 2);
  EXPECT_NEAR(c.K_cr, bf.KCritical(0.0), 1e-6 * c.K_cr);
  // Table I rounds m = 1/856 to 0.001168 (and b = 5/856 to 0.00584): 2.34105.
  EXPECT_NEAR(c.K_cr, 2.34105, 5e-6);
  EXPECT_NEAR(c.f_cr_hz, 7.10, 0.01);
  // The issue's 2.3415 at 7.10 Hz is the appendix's G0 = 856 / (s^2 + 5 s)
  // itself (also SciPy's cont2discrete and numpy.roots: 2.341497).
  p.m = 1.0 / 856.0;
  p.b = 5.0 / 856.0;
  const CriticalPoint a = ZWidth(p, 1e-3, 2).At(0.0);
  EXPECT_NEAR(a.K_cr, 2.3415, 5e-5);
  EXPECT_NEAR(a.f_cr_hz, 7.10, 0.01);
}

class ZWidthDelays : public ::testing::TestWithParam<int> {};

TEST_P(ZWidthDelays, AgreesWithBruteForceOverDelaysAndDampings) {
  const model::Plant p = model::PhantomTable1();
  const int d = GetParam();
  const ZWidth z(p, 1e-3, d);
  const BruteForce bf(p, 1e-3, d);
  for (int i = 0; i <= 800; ++i) {
    const double B = 0.0005 * i;
    const CriticalPoint c = z.At(B);
    EXPECT_TRUE(c.verified) << d << " " << B;
    if (c.K_cr > 0 && std::isfinite(c.K_cr)) {
      // Root check at +-1e-6 relative, for every point.
      EXPECT_LT(bf.MaxRoot(c.K_cr * (1 - 1e-6), B), 1.0) << d << " " << B;
      EXPECT_GE(bf.MaxRoot(c.K_cr * (1 + 1e-6), B), 1.0) << d << " " << B;
    } else if (c.K_cr == 0) {
      EXPECT_GE(bf.MaxRoot(1e-4, B), 1.0) << d << " " << B;
    }
    if (i % 80 == 0) {  // full scan: also the *first* crossing
      const double ref = bf.KCritical(B);
      if (ref == 0) EXPECT_EQ(c.K_cr, 0.0) << d << " " << B;
      else EXPECT_NEAR(c.K_cr, ref, 1e-6 * ref) << d << " " << B;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(OneToTen, ZWidthDelays, ::testing::Range(1, 11), test::DelayName());

TEST(ZWidth, MarginReadingStaysPositivePastBMax) {
  const ZWidth z(model::PhantomTable1(), 1e-3, 2);
  const CriticalPoint c = z.At(0.15);
  EXPECT_EQ(c.K_cr, 0.0);
  EXPECT_TRUE(c.unstable_at_zero_k);
  EXPECT_GT(c.K_margin, 0.0);
  EXPECT_FALSE(c.AgreesWithMargin());
  const CriticalPoint ok = z.At(0.05);
  EXPECT_TRUE(ok.AgreesWithMargin());
}

TEST(ZWidth, DegenerateCases) {
  EXPECT_THROW(ZWidth(model::PhantomTable1(), 0.0, 2), InputError);
  EXPECT_THROW(ZWidth(model::PhantomTable1(), 1e-3, -1), InputError);
  // The pole at z = 1: K < 0 is never stable; K = 0+ at B = 0 is.
  const ZWidth z(model::PhantomTable1(), 1e-3, 2);
  EXPECT_FALSE(z.IsStable(-1e-6, 0.0));
  EXPECT_TRUE(z.IsStable(0.0, 0.0));
}

// The Z-width as the exact stable region (issue 13): the stable K intervals per
// B against an independent brute force (closed-loop roots as companion-matrix
// eigenvalues, tests/brute_force.h), B_max, the B grid, and the delta-method
// std against Monte Carlo.
// The issue's first example device (m 2e-3, three modes, own delay 1): tests/devices.h.
using test::IssueDeviceOne;
// The second (two lightly damped modes).
model::Plant IssueDeviceTwo() {
  model::Plant p;
  p.m = 1.53e-3;
  p.b = 6.609e-3;
  p.modes = {{745.28, 0.15689, 626.46, 0.36921}, {1026.0, 1.8126, 827.44, 0.45092}};
  return p;
}

// 120 values of B up to 1.3 B_max, 20 points inside each interval
// (tests/brute_force.h's Classify).
Tally Classify(const model::Plant& p, int delay, int min_points) {
  const double T = 1e-3;
  const ZWidth z(p, T, delay);
  const BruteForce bf(p, T, delay);
  const DelaySummary s = z.Summarize();
  const ClassifyGrid g{1.3 * std::max(s.B_max, 1e-6 * p.m / T), 120, min_points, 20};
  return stability::Classify(z, [&](double K, double B) { return bf.MaxRoot(K, B); }, p, T, delay, g);
}

TEST(StableIntervals, AgreeWithEigenvaluesOnRandomDevicesAndTheIssuesExamples) {
  std::mt19937_64 rng(20261127);
  struct Case { model::Plant p; int d; };
  std::vector<Case> cases = {{IssueDeviceOne(), 4}, {IssueDeviceTwo(), 5}, {model::PhantomTable1(), 2}};
  std::uniform_int_distribution<int> delay(0, 20);
  for (int k = 0; k < 8; ++k) cases.push_back({test::RandomPlausibleDevice(rng, k % 4), k == 0 ? 0 : k == 1 ? 20 : delay(rng)});
  long total = 0, reopened = 0, near = 0;
  for (const Case& c : cases) {
    const Tally t = Classify(c.p, c.d, 20000);
    EXPECT_GE(t.points, 20000);
    EXPECT_EQ(t.disagree, 0) << c.p.modes.size() << " modes, d = " << c.d;
    EXPECT_GT(t.stable, 1000);
    EXPECT_GT(t.points - t.stable, 100);
    total += t.points;
    reopened += t.reopened;
    near += t.near_boundary;
  }
  // Points in bands that start above K = 0 were classified too.
  EXPECT_GT(reopened, 2000);
  std::printf("%ld points, %ld in intervals starting above 0, %ld within 1e-6 of a boundary\n", total, reopened,
              near);
}

// RowAt computes the crossings once and each stability test once: it must give
// exactly At(B) and StableIntervals(B) (bit for bit, the verification flags
// included), on random devices and delays, with and without a velocity filter
// and a hand, over B from 0 to past B_max.
TEST(StableIntervals, RowAtIsAtAndStableIntervalsTogether) {
  std::mt19937_64 rng(20261128);
  std::uniform_int_distribution<int> delay(0, 12);
  auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  long with_two = 0;
  for (int k = 0; k < 12; ++k) {
    const model::Plant p = k == 0 ? IssueDeviceOne() : test::RandomPlausibleDevice(rng, k % 4);
    const double T = 1e-3;
    LoopOptions loop;
    if (k % 3 == 1) SetLowPassFilter(30.0 + 10.0 * k, T, &loop);
    if (k % 3 == 2) loop.hand = {0.5 * p.m, p.b, 10.0 * p.m};
    const ZWidth z(p, T, k == 0 ? 4 : delay(rng), loop);
    const double top = 1.2 * std::max(z.Summarize().B_max, 1e-3 * p.m / T);
    for (int i = 0; i <= 150; ++i) {
      const double B = top * i / 150.0;
      const ZWidth::Row r = z.RowAt(B);
      const CriticalPoint c = z.At(B);
      const std::vector<KInterval> iv = z.StableIntervals(B);
      const std::string at = "device " + std::to_string(k) + " B = " + std::to_string(B);
      EXPECT_TRUE(same(r.point.K_cr, c.K_cr) && same(r.point.f_cr_hz, c.f_cr_hz) &&
                  same(r.point.K_margin, c.K_margin) && same(r.point.f_margin_hz, c.f_margin_hz) &&
                  r.point.verified == c.verified && r.point.unstable_at_zero_k == c.unstable_at_zero_k && r.point.B == c.B)
          << at;
      ASSERT_EQ(r.intervals.size(), iv.size()) << at;
      for (size_t j = 0; j < iv.size(); ++j) {
        EXPECT_TRUE(same(r.intervals[j].K_lo, iv[j].K_lo) && same(r.intervals[j].K_hi, iv[j].K_hi) &&
                    same(r.intervals[j].f_lo_hz, iv[j].f_lo_hz) && same(r.intervals[j].f_hi_hz, iv[j].f_hi_hz) &&
                    r.intervals[j].verified == iv[j].verified)
            << at << " interval " << j;
      }
      if (iv.size() > 1 || (!iv.empty() && iv[0].K_lo > 0)) ++with_two;
    }
  }
  EXPECT_GT(with_two, 0);  // rows with an interval starting above 0 were compared too
}

TEST(StableIntervals, TheIssuesReopenedBands) {
  // Example 1: past B_max_from_zero ~ 0.4998 the band (1.82, 23.5) at
  // B = 0.5005 and (12.3, 23.0) at 0.505 (the issue's rounded values).
  const ZWidth z1(IssueDeviceOne(), 1e-3, 4);
  const DelaySummary s1 = z1.Summarize();
  EXPECT_NEAR(s1.B_max_from_zero, 0.4998, 1e-4);
  EXPECT_GT(s1.B_max, 0.505);
  ASSERT_FALSE(s1.reopened_bands.empty());
  std::vector<KInterval> iv = z1.StableIntervals(0.5005);
  ASSERT_EQ(iv.size(), 1u);
  EXPECT_NEAR(iv[0].K_lo, 1.82, 0.05);
  EXPECT_NEAR(iv[0].K_hi, 23.5, 0.1);
  EXPECT_TRUE(iv[0].verified);
  iv = z1.StableIntervals(0.505);
  ASSERT_EQ(iv.size(), 1u);
  EXPECT_NEAR(iv[0].K_lo, 12.3, 0.1);
  EXPECT_NEAR(iv[0].K_hi, 23.0, 0.1);
  EXPECT_TRUE(z1.IsStable(10.0, 0.5005));
  // Example 2: at 3 B_max_from_zero about (2.79, 4.47).
  const ZWidth z2(IssueDeviceTwo(), 1e-3, 5);
  const DelaySummary s2 = z2.Summarize();
  EXPECT_NEAR(s2.B_max_from_zero, 0.0062, 1e-4);
  iv = z2.StableIntervals(3 * s2.B_max_from_zero);
  ASSERT_EQ(iv.size(), 1u);
  EXPECT_NEAR(iv[0].K_lo, 2.79, 0.02);
  EXPECT_NEAR(iv[0].K_hi, 4.47, 0.02);
}

TEST(StableIntervals, NothingIsStableJustPastBMax) {
  // B_max against the brute force: past it a dense K scan finds no stable K,
  // just before it the intervals' midpoint is stable by eigenvalues.
  std::mt19937_64 rng(7);
  std::vector<std::pair<model::Plant, int>> cases = {{IssueDeviceOne(), 4}, {IssueDeviceTwo(), 5}, {model::PhantomTable1(), 2}};
  for (int k = 0; k < 4; ++k) cases.push_back({test::RandomPlausibleDevice(rng, 1 + k % 3), 1 + 3 * k});
  for (const auto& [p, d] : cases) {
    const ZWidth z(p, 1e-3, d);
    const BruteForce bf(p, 1e-3, d);
    const DelaySummary s = z.Summarize();
    ASSERT_TRUE(std::isfinite(s.B_max));
    ASSERT_GT(s.B_max, 0.0);
    const double below = s.B_max * (1 - 1e-5);
    const std::vector<KInterval> iv = z.StableIntervals(below);
    ASSERT_FALSE(iv.empty()) << d;
    const double mid = std::sqrt(std::max(iv.back().K_lo, 1e-9 * iv.back().K_hi) * iv.back().K_hi);
    EXPECT_LT(bf.MaxRoot(mid, below), 1.0) << d;
    const double above = s.B_max * (1 + 1e-4);
    EXPECT_TRUE(z.StableIntervals(above).empty()) << d;
    double kmax = 0.0;
    for (const Crossing& x : z.Crossings(0.0)) if (std::isfinite(x.K)) kmax = std::max(kmax, x.K);
    for (int j = 0; j < 2000; ++j) {
      const double K = 1e-6 * p.m * 1e6 * std::pow(1e12, j / 1999.0);  // 1e-6 .. 1e6 x m/T^2
      ASSERT_GE(bf.MaxRoot(K, above), 1.0) << d << " K=" << K;
    }
  }
}

TEST(StableIntervals, KcrIsTheUpperEndOfTheIntervalFromZero) {
  const ZWidth z(model::PhantomTable1(), 1e-3, 2);
  for (double B : {0.0, 0.02, 0.05, 0.09, 0.099, 0.12}) {
    const CriticalPoint c = z.At(B);
    const std::vector<KInterval> iv = z.StableIntervals(B);
    if (c.K_cr == 0.0) {
      EXPECT_TRUE(iv.empty() || iv[0].K_lo > 0.0) << B;
    } else {
      ASSERT_FALSE(iv.empty());
      EXPECT_EQ(iv[0].K_lo, 0.0);
      EXPECT_DOUBLE_EQ(iv[0].K_hi, c.K_cr) << B;
    }
  }
}

TEST(BGrid, ScalesWithTheDeviceAndRefusesHugeGrids) {
  BGridOptions o;
  std::vector<double> g = MakeBGrid(o, 2.0e4, 1.0, 3);
  ASSERT_EQ(g.size(), 1000u);
  EXPECT_EQ(g.front(), 0.0);
  EXPECT_DOUBLE_EQ(g.back(), 2.1e4);
  o.b_step = 0.5;
  o.b_max = 10.0;
  g = MakeBGrid(o, 2.0e4, 1.0, 3);
  EXPECT_EQ(g.size(), 21u);
  o.b_max = 1e300;
  EXPECT_THROW(MakeBGrid(o, 1.0, 1.0, 1), InputError);
  o.b_step = 1e-300;
  o.b_max = 1.0;
  EXPECT_THROW(MakeBGrid(o, 1.0, 1.0, 1), InputError);
  o.b_step = std::numeric_limits<double>::quiet_NaN();
  o.b_points = 1;
  EXPECT_THROW(MakeBGrid(o, 1.0, 1.0, 1), InputError);
  EXPECT_TRUE(BGridOptions{}.IsValid(nullptr));
}

}  // namespace
}  // namespace zwidth::stability
