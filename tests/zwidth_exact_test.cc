// Issue 31: the Z-width stays exact with many lightly damped modes crowded
// together, where the characteristic polynomial cannot locate its roots.
// Against a brute force independent of the code under test: the test's own
// realisation of eq. (1) (rigid body first, then each section in a transposed
// form; stability/ and model/state_space.cc realise it the other way round),
// sampled by Eigen's matrix exponential without balancing, closed by
// tests/brute_force.h's LoopBruteForce (its own loop matrix with y_{k-1} as a
// state), stable when every eigenvalue has |z| < 1. Where its double
// eigenvalues disagree with the Z-width, the same brute force in long double
// decides (the referee of tests/brute_force.h's Classify).
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "model/plant.h"
#include "stability/haptic_loop.h"
#include "stability/zwidth.h"
#include "tests/brute_force.h"

namespace zwidth::stability {
namespace {

// The issue's family: n sections, omega_i = w0 ratio^i, damping ratio zeta
// for poles and zeros, v_i = 0.93 omega_i, Table I's m and b.
model::Plant Family(int n, double w0, double ratio, double zeta) {
  model::Plant p;
  p.m = 1.168e-3;
  p.b = 0.00584;
  for (int i = 0; i < n; ++i) {
    const double w = w0 * std::pow(ratio, i), v = 0.93 * w;
    p.modes.push_back({w, 2 * zeta * w, v, 2 * zeta * v});
  }
  return p;
}

// u -> rigid body (theta, theta') -> section 1 -> ... -> y. Section (x1, x2):
// x1' = -c x1 - w x2 + in, x2' = w x1, out = g ((d - c) x1 + (v^2 - w^2)/w x2 + in),
// g = w^2 / v^2: (sI - A)^-1 e1 = (s, w) / (s^2 + c s + w^2), so out / in =
// g (s^2 + d s + v^2) / (s^2 + c s + w^2).
// R = long double: the referee (tests/brute_force.h), the same realisation
// and ZOH in 64-bit-mantissa arithmetic.
template <typename R = double>
LoopBruteForceT<R> IndependentBrute(const model::Plant& p, int delay, double T_, const LoopOptions& loop = {}) {
  using Mat = typename LoopBruteForceT<R>::Mat;
  using Vec = typename LoopBruteForceT<R>::Vec;
  using Row = typename LoopBruteForceT<R>::Row;
  const R T = T_, m = p.m, b = p.b;
  const int n = 2 + 2 * static_cast<int>(p.modes.size());
  Mat A = Mat::Zero(n, n);
  Vec Bc = Vec::Zero(n);
  A(0, 1) = R(1);
  A(1, 1) = -b / m;
  Bc(1) = R(1) / m;
  Row out = Row::Zero(n);
  out(0) = R(1);
  for (size_t k = 0; k < p.modes.size(); ++k) {
    const R w = p.modes[k].omega, c = p.modes[k].c, v = p.modes[k].v, d = p.modes[k].d;
    const int i = 2 + 2 * static_cast<int>(k);
    A(i, i) = -c;
    A(i, i + 1) = -w;
    A(i + 1, i) = w;
    A.row(i) += out;
    const R g = w * w / (v * v);
    Row next = g * out;
    next(i) += g * (d - c);
    next(i + 1) += g * (v * v - w * w) / w;
    out = next;
  }
  Mat M = Mat::Zero(n + 1, n + 1);
  M.topLeftCorner(n, n) = A * T;
  M.topRightCorner(n, 1) = Bc * T;
  const Mat E = M.exp();
  return LoopBruteForceT<R>(E.topLeftCorner(n, n), E.topRightCorner(n, 1), out, loop.filter_b, loop.filter_a,
                            delay + p.delay_samples, T_);
}

// Smallest K > 0 at which the brute force has a root on the circle: the
// first unstable K of a geometric scan from k_lo, then 60 bisections.
double BruteKcr(const LoopBruteForce& bf, double B, double k_lo) {
  double prev = k_lo;
  for (double k = k_lo * 1.02; k < 1e7; k *= 1.02) {
    if (bf.MaxRoot(k, B) >= 1.0) {
      double a = prev, b = k;
      for (int i = 0; i < 60; ++i) ((bf.MaxRoot(0.5 * (a + b), B) >= 1.0) ? b : a) = 0.5 * (a + b);
      return 0.5 * (a + b);
    }
    prev = k;
  }
  return INFINITY;
}

TEST(ZWidthExact, TheIssuesClusteredFamiliesGiveTheEigenvaluesKcr) {
  // The issue's figures (exact ZOH state space with the delay as states).
  for (const auto& [n, expected] : {std::pair{8, 2.46406}, std::pair{64, 2.59895}}) {
    const model::Plant p = Family(n, 300.0, 1.08, 0.025);
    const ZWidth z(p, 1e-3, 2);
    const double k = z.At(0.0).K_cr;
    EXPECT_NEAR(k, expected, 5e-6) << n << " sections";
    const double brute = BruteKcr(IndependentBrute(p, 2, 1e-3), 0.0, 1e-3);
    EXPECT_NEAR(k / brute, 1.0, 1e-6) << n << " sections";
    EXPECT_TRUE(z.At(0.0).verified);
    // The walls of `check` in the issue, and every caller's one test.
    for (double B : {0.0, 0.02}) {
      EXPECT_TRUE(z.IsStable(1.0, B)) << n << " sections, B = " << B;
      const std::vector<KInterval> iv = z.StableIntervals(B);
      ASSERT_FALSE(iv.empty());
      EXPECT_EQ(iv[0].K_lo, 0.0);
      EXPECT_GT(iv[0].K_hi, 1.0);
    }
  }
}

TEST(ZWidthExact, SevenSectionsIsStableAgreesWithStableIntervals) {
  const ZWidth z(Family(7, 300.0, 1.08, 0.025), 1e-3, 2);
  const std::vector<KInterval> iv = z.StableIntervals(0.0);
  ASSERT_FALSE(iv.empty());
  EXPECT_TRUE(z.IsStable(1.0, 0.0));
  EXPECT_TRUE(z.IsStable(0.5, 0.0));
  EXPECT_NEAR(iv[0].K_hi / BruteKcr(IndependentBrute(Family(7, 300.0, 1.08, 0.025), 2, 1e-3), 0.0, 1e-3), 1.0, 1e-6);
}

TEST(ZWidthExact, PolynomialTestOnlyWhereItsRootsAreWellPlaced) {
  // Table I keeps the O(n^2) Schur-Cohn test; the crowded family does not.
  const ZWidth few(model::PhantomTable1(), 1e-3, 2);
  EXPECT_TRUE(few.uses_polynomial_test());
  EXPECT_LE(few.polynomial_error(), kPolynomialRelativeTolerance);
  const ZWidth many(Family(8, 300.0, 1.08, 0.025), 1e-3, 2);
  EXPECT_FALSE(many.uses_polynomial_test());
  std::printf("pole shift: Table I %g, 8 sections %g; boundary error: Table I %g\n",
              few.sampled_plant().denominator_pole_shift(), many.sampled_plant().denominator_pole_shift(),
              few.polynomial_error());
}

// The frequency [Hz] of the brute force's largest root just past K.
double BruteFrequency(const LoopBruteForce& bf, double K, double B, double T) {
  const Eigen::VectorXcd ev = bf.Matrix(K, B).eigenvalues();
  int i = 0;
  ev.cwiseAbs().maxCoeff(&i);
  return std::abs(std::arg(ev(i))) / (2 * std::numbers::pi * T);
}

// Issue 29, item 4: a 3-mode device (from a seeded random search over
// 3-mode devices for two jumps of f_CR) whose f_CR jumps first at B = 0.136,
// K_CR 46.1, while K_CR rises on to its peak at a second jump, B = 0.215.
TEST(Summary, BtIsWhereKcrPeaksAsTheFrequencyJumps) {
  model::Plant p;
  p.m = 1.168e-3;
  p.b = 0.00584;
  p.modes = {{348.995, 31.662, 280.335, 28.0335}, {592.106, 161.391, 470.544, 47.0544},
             {1261.05, 529.63, 943.803, 94.3803}};
  const double T = 1e-3;
  const DelaySummary s = ZWidth(p, T, 2).Summarize();
  ASSERT_EQ(s.frequency_jumps.size(), 2u);
  const LoopBruteForce bf = IndependentBrute(p, 2, T);
  for (const FrequencyJump& j : s.frequency_jumps) {
    // Each side of each jump: the brute force's K_CR and the frequency of its critical root.
    const double kb = BruteKcr(bf, j.B * (1 - 1e-5), 1e-2), ka = BruteKcr(bf, j.B * (1 + 1e-5), 1e-2);
    EXPECT_NEAR(kb / j.K_before, 1.0, 1e-4) << j.B;
    EXPECT_NEAR(ka / j.K_after, 1.0, 1e-4) << j.B;
    EXPECT_NEAR(BruteFrequency(bf, kb * (1 + 1e-7), j.B * (1 - 1e-5), T), j.f_before_hz, 0.01 * j.f_before_hz);
    EXPECT_NEAR(BruteFrequency(bf, ka * (1 + 1e-7), j.B * (1 + 1e-5), T), j.f_after_hz, 0.01 * j.f_after_hz);
    EXPECT_GT(std::abs(std::log(j.f_after_hz / j.f_before_hz)), std::log(1.5));
  }
  EXPECT_LT(s.frequency_jumps[0].B, s.frequency_jumps[1].B);
  // B_t is the second jump, where K_CR peaks: the brute force's K_CR on a
  // 60-point grid over [0, B_max_from_zero) stays below K_cr_max.
  EXPECT_EQ(s.B_t, s.frequency_jumps[1].B);
  EXPECT_NEAR(s.B_t, 0.215054, 1e-5);
  EXPECT_NEAR(s.B_at_K_cr_max, s.B_t, 1e-6 * s.B_t);
  EXPECT_EQ(s.f_before_hz, s.frequency_jumps[1].f_before_hz);
  double brute_max = 0.0;
  for (int i = 0; i < 60; ++i) brute_max = std::max(brute_max, BruteKcr(bf, s.B_max_from_zero * i / 60.0, 1e-2));
  EXPECT_LE(brute_max, s.K_cr_max * (1 + 1e-6));
  EXPECT_GT(brute_max, s.frequency_jumps[0].K_before * 1.05);
}

struct FamilyCase {
  std::string name;
  int sections;
  double w0, ratio, zeta;
  int delay;
  bool filter;  // a 50 Hz first-order velocity low-pass
};

class ZWidthFamilies : public ::testing::TestWithParam<FamilyCase> {};

TEST_P(ZWidthFamilies, IntervalsAgreeWithIndependentEigenvaluesOnAGrid) {
  const FamilyCase& c = GetParam();
  const double T = 1e-3;
  const model::Plant p = Family(c.sections, c.w0, c.ratio, c.zeta);
  LoopOptions loop;
  if (c.filter) SetLowPassFilter(50.0, T, &loop);
  const ZWidth z(p, T, c.delay, loop);
  const LoopBruteForce bf = IndependentBrute(p, c.delay, T, loop);
  const double b_max = z.Summarize().B_max;
  ClassifyGrid g;
  g.b_top = std::isfinite(b_max) && b_max > 0 ? 1.1 * b_max : 0.1;
  g.num_b = c.sections >= 32 ? 4 : 7;
  g.min_points = c.sections >= 32 ? 60 : 150;
  g.points_inside = 2;
  std::printf("%s: %s test, pole shift %.3g, boundary error %.3g\n", c.name.c_str(),
              z.uses_polynomial_test() ? "Schur-Cohn" : "eigenvalue", z.sampled_plant().denominator_pole_shift(),
              z.polynomial_error());
  const LoopBruteForceT<long double> referee = IndependentBrute<long double>(p, c.delay, T, loop);
  const Tally t = Classify(z, [&](double K, double B) { return bf.MaxRoot(K, B); }, p, T, c.delay, g,
                           [&](double K, double B) { return referee.MaxRoot(K, B); });
  std::printf("%s: %ld points, %ld stable, %ld near a boundary, %ld decided by the long double referee\n",
              c.name.c_str(), t.points, t.stable, t.near_boundary, t.refereed);
  EXPECT_EQ(t.disagree, 0);
  EXPECT_GT(t.stable, 0) << "the grid must reach the stable region";
  EXPECT_LT(t.stable, t.points) << "and the unstable one";
}

#ifndef ZWIDTH_MANY_MODES
INSTANTIATE_TEST_SUITE_P(
    ClusteredModes, ZWidthFamilies,
    ::testing::Values(FamilyCase{"one_section_zeta1e4_d0", 1, 300, 1.08, 1e-4, 0, false},
                      FamilyCase{"two_sections_1pct_zeta1e4_d2", 2, 300, 1.01, 1e-4, 2, false},
                      FamilyCase{"three_sections_1pct_zeta01_d20", 3, 600, 1.01, 0.1, 20, false},
                      FamilyCase{"five_sections_3pct_zeta1e3_d4_filter", 5, 400, 1.03, 1e-3, 4, true},
                      FamilyCase{"eight_sections_8pct_zeta0025_d2", 8, 300, 1.08, 0.025, 2, false},
                      FamilyCase{"eight_sections_1pct_zeta1e4_d8", 8, 300, 1.01, 1e-4, 8, false},
                      FamilyCase{"twelve_sections_2pct_zeta01_d1", 12, 800, 1.02, 0.1, 1, false},
                      FamilyCase{"sixteen_sections_4pct_zeta001_d20_filter", 16, 300, 1.04, 0.01, 20, true}),
    [](const ::testing::TestParamInfo<FamilyCase>& i) { return i.param.name; });
#else
// 32 and 64 sections: the eigenvalue test is O(n^3), so in the stress label
// (zwidth_exact_stress_test). Measured under load 15 on 2 cores: 6.6 s and
// 39 s (was 10.5 s with one false point, and 361 s). Open (issue 31): 64
// sections 1 % apart at damping 1e-4 (d = 0) does not finish in 10.8 CPU
// minutes, 99 % of it in the crossings' Hessenberg solves
// (model::DiscreteResponse::AtZ), so it is not in the suite yet.
INSTANTIATE_TEST_SUITE_P(
    ManyModes, ZWidthFamilies,
    ::testing::Values(FamilyCase{"thirtytwo_sections_1pct_zeta1e3_d3", 32, 500, 1.01, 1e-3, 3, false},
                      FamilyCase{"sixtyfour_sections_8pct_zeta0025_d2", 64, 300, 1.08, 0.025, 2, false}),
    [](const ::testing::TestParamInfo<FamilyCase>& i) { return i.param.name; });
#endif

}  // namespace
}  // namespace zwidth::stability
