// The Z-width as the exact stable region (issue 13): the stable K intervals per
// B against an independent brute force (closed-loop roots as companion-matrix
// eigenvalues, tests/brute_force.h), B_max, the B grid, and the delta-method
// std against Monte Carlo.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"
#include "tests/brute_force.h"
#include "tests/test_util.h"

namespace zwidth::stability {
namespace {

// The issue's first example device (m 2e-3, three modes, own delay 1).
Plant IssueDeviceOne() {
  Plant p;
  p.m = 2e-3;
  p.b = 0.008;
  p.delay_samples = 1;
  p.modes = {{439.82, 70.4, 389.56, 46.7}, {942.48, 150.8, 848.23, 101.8}, {1633.63, 261.4, 1507.96, 181.0}};
  return p;
}
// The second (two lightly damped modes).
Plant IssueDeviceTwo() {
  Plant p;
  p.m = 1.53e-3;
  p.b = 6.609e-3;
  p.modes = {{745.28, 0.15689, 626.46, 0.36921}, {1026.0, 1.8126, 827.44, 0.45092}};
  return p;
}

// 120 values of B up to 1.3 B_max, 20 points inside each interval
// (tests/brute_force.h's Classify).
Tally Classify(const Plant& p, int delay, int min_points) {
  const double T = 1e-3;
  const ZWidth z(p, T, delay);
  const BruteForce bf(p, T, delay);
  const DelaySummary s = z.Summarize();
  const ClassifyGrid g{1.3 * std::max(s.B_max, 1e-6 * p.m / T), 120, min_points, 20};
  return stability::Classify(z, [&](double K, double B) { return bf.MaxRoot(K, B); }, p, T, delay, g);
}

TEST(StableIntervals, AgreeWithEigenvaluesOnRandomDevicesAndTheIssuesExamples) {
  std::mt19937_64 rng(20261127);
  struct Case { Plant p; int d; };
  std::vector<Case> cases = {{IssueDeviceOne(), 4}, {IssueDeviceTwo(), 5}, {PhantomTable1(), 2}};
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
  std::vector<std::pair<Plant, int>> cases = {{IssueDeviceOne(), 4}, {IssueDeviceTwo(), 5}, {PhantomTable1(), 2}};
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
  const ZWidth z(PhantomTable1(), 1e-3, 2);
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

// A covariance with 1-2% relative std and some correlation, seeded.
std::vector<double> TestCovariance(const Plant& p, double rel_std, unsigned seed) {
  const int n = NumLogParameters(p);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i) for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  Eigen::MatrixXd S = 0.3 * A * A.transpose() / n + Eigen::MatrixXd::Identity(n, n);
  S *= rel_std * rel_std;
  return std::vector<double>(S.data(), S.data() + n * n);
}

TEST(Uncertainty, DeltaMethodAgreesWithMonteCarlo) {
  // Table I at d = 2 (a transition and an interior-free K_CR^max at B_t) and
  // d = 8, 1% relative std; 300 seeded samples (std of a sample std ~ 4%).
  const Plant p = PhantomTable1();
  const std::vector<double> cov = TestCovariance(p, 0.01, 3);
  for (int d : {2, 8}) {
    const ZWidth z(p, 1e-3, d);
    const DelaySummary s = z.Summarize();
    const SummaryStd dm = SummaryStdDelta(p, cov, 1e-3, d, s);
    const MonteCarloResult mc = SummaryMonteCarlo(p, cov, 1e-3, d, 300, 11);
    const double pairs[4][2] = {{dm.K_cr_at_zero_B, mc.std.K_cr_at_zero_B}, {dm.B_t, mc.std.B_t},
                                {dm.K_cr_max, mc.std.K_cr_max}, {dm.B_max, mc.std.B_max}};
    for (int q = 0; q < 4; ++q) {
      if (q == 1 && !s.has_transition) continue;
      ASSERT_TRUE(std::isfinite(pairs[q][0]) && pairs[q][0] > 0) << d << " " << q;
      EXPECT_LT(pairs[q][0] / pairs[q][1], 1.5) << "d=" << d << " quantity " << q;
      EXPECT_GT(pairs[q][0] / pairs[q][1], 1 / 1.5) << "d=" << d << " quantity " << q;
      std::printf("d=%d q=%d delta %.4g monte carlo %.4g ratio %.3f\n", d, q, pairs[q][0], pairs[q][1],
                  pairs[q][0] / pairs[q][1]);
    }
    // K_CR(B) at a few B below the transition: implicit differentiation
    // against Monte Carlo of At(B).
    std::vector<CriticalPoint> pts;
    for (double f : {0.0, 0.3, 0.6}) pts.push_back(z.At(f * (s.has_transition ? s.B_t : s.B_max_from_zero)));
    const std::vector<double> sd = KcrStd(p, cov, 1e-3, d, pts);
    const int n = NumLogParameters(p);
    const Eigen::MatrixXd S = Eigen::Map<const Eigen::MatrixXd>(cov.data(), n, n);
    const Eigen::MatrixXd L = S.llt().matrixL();
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g;
    std::vector<double> s1(pts.size()), s2(pts.size());
    const int N = 400;
    for (int k = 0; k < N; ++k) {
      Eigen::VectorXd u(n);
      for (int i = 0; i < n; ++i) u[i] = g(rng);
      const Eigen::VectorXd dx = L * u;
      const ZWidth zs(PerturbLog(p, std::vector<double>(dx.data(), dx.data() + n)), 1e-3, d);
      for (size_t j = 0; j < pts.size(); ++j) {
        const double v = zs.At(pts[j].B).K_cr - pts[j].K_cr;
        s1[j] += v;
        s2[j] += v * v;
      }
    }
    for (size_t j = 0; j < pts.size(); ++j) {
      const double m = s1[j] / N, mc_sd = std::sqrt((s2[j] - N * m * m) / (N - 1));
      EXPECT_LT(sd[j] / mc_sd, 1.5) << d << " B=" << pts[j].B;
      EXPECT_GT(sd[j] / mc_sd, 1 / 1.5) << d << " B=" << pts[j].B;
    }
  }
}

TEST(Uncertainty, RejectsABadCovariance) {
  const Plant p = PhantomTable1();
  EXPECT_THROW(CheckLogCovariance(p, {1.0, 0.0}), InputError);
  std::vector<double> c = TestCovariance(p, 0.01, 1);
  c[1] += 1.0;  // not symmetric
  EXPECT_THROW(CheckLogCovariance(p, c), InputError);
  const int n = NumLogParameters(p);
  std::vector<double> neg(n * n, 0.0);
  neg[0] = -1.0;
  EXPECT_THROW(CheckLogCovariance(p, neg), InputError);
}

}  // namespace
}  // namespace zwidth::stability
