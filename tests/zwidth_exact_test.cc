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
#include <complex>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "model/plant.h"
#include "model/state_space_internal.h"
#include "stability/loop_options.h"
#include "stability/velocity_filter.h"
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

// The test's own realisation and ZOH (tests/brute_force.h, IndependentZoh),
// closed by LoopBruteForceT. R = long double: the referee (tests/brute_force.h),
// the same realisation and ZOH in 64-bit-mantissa arithmetic.
template <typename R = double>
LoopBruteForceT<R> IndependentBrute(const model::Plant& p, int delay, double T_, const LoopOptions& loop = {}) {
  const IndependentZoh<R> zoh(p, T_);
  return LoopBruteForceT<R>(zoh.A, zoh.B, zoh.C, loop.filter_b, loop.filter_a, delay + p.delay_samples, T_);
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

// The conditioning of PoleConditioning recomputed independently: the poles
// from the modes (e^{pT}: 1, e^{-bT/m}, each mode's pair), kappa_i from left
// eigenvectors of A^T by a second eigensolver (not V^-1), paired with the
// right ones by nearest eigenvalue, and each pole's distance to the circle
// from its exact modulus.
PoleConditioning IndependentConditioning(const model::Plant& p, const SampledPlant& sp) {
  const double T = sp.period_s();
  std::vector<std::complex<double>> exact = {1.0, std::exp(-p.b / p.m * T)};
  for (const model::Mode& md : p.modes) {
    const std::complex<double> s(-md.c / 2, std::sqrt(md.omega * md.omega - md.c * md.c / 4));
    exact.push_back(std::exp(s * T));
    exact.push_back(std::exp(std::conj(s) * T));
  }
  PoleConditioning c;
  double gap = INFINITY, spread = 0.0;
  for (size_t i = 0; i < exact.size(); ++i)
    for (size_t j = i + 1; j < exact.size(); ++j) {
      gap = std::min(gap, std::abs(exact[i] - exact[j]));
      spread = std::max(spread, std::abs(exact[i] - exact[j]));
    }
  c.relative_separation = gap / spread;
  const Eigen::MatrixXd& A = sp.discrete().A;
  const Eigen::VectorXd sc = model::internal::BalancingScales(A);
  const Eigen::MatrixXd Ab = sc.cwiseInverse().asDiagonal() * A * sc.asDiagonal();
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> right(Ab.cast<std::complex<double>>()),
      left(Ab.transpose().cast<std::complex<double>>());
  c.eigenvalue_condition = 0.0;
  c.eigenvalue_shift = 0.0;
  for (int i = 0; i < Ab.rows(); ++i) {
    const std::complex<double> z = right.eigenvalues()(i);
    int j = 0, k = 0;
    (left.eigenvalues().array() - z).abs().minCoeff(&j);
    double best = INFINITY;
    for (size_t e = 0; e < exact.size(); ++e)
      if (std::abs(exact[e] - z) < best) { best = std::abs(exact[e] - z); k = static_cast<int>(e); }
    const Eigen::VectorXcd x = right.eigenvectors().col(i), y = left.eigenvectors().col(j);
    const double kappa = x.norm() * y.norm() / std::abs((y.transpose() * x).value());
    c.eigenvalue_condition = std::max(c.eigenvalue_condition, kappa);
    if (k == 0) continue;  // the integrator
    c.eigenvalue_shift = std::max(c.eigenvalue_shift, 2.220446049250313e-16 * Ab.norm() * kappa / (1 - std::abs(exact[k])));
  }
  return c;
}

TEST(ZWidthExact, ConditioningWarnsForCrowdedModesOnly) {
  const double T = 1e-3;
  struct Case { const char* name; model::Plant plant; bool warns; };
  const std::vector<Case> cases = {{"Table I", model::PhantomTable1(), false},
                                   {"3 sections 30 % apart", Family(3, 300.0, 1.3, 0.05), false},
                                   {"64 sections 1 % apart, damping 1e-4", Family(64, 300.0, 1.01, 1e-4), true}};
  for (const Case& c : cases) {
    const SampledPlant sp(c.plant, T);
    const PoleConditioning& got = sp.conditioning();
    const PoleConditioning ref = IndependentConditioning(c.plant, sp);
    std::printf("%s: relative separation %.3g (independent %.3g), eigenvalue condition %.3g (%.3g), "
                "shift %.3g (%.3g)\n", c.name, got.relative_separation, ref.relative_separation,
                got.eigenvalue_condition, ref.eigenvalue_condition, got.eigenvalue_shift, ref.eigenvalue_shift);
    EXPECT_NEAR(got.relative_separation / ref.relative_separation, 1.0, 1e-3) << c.name;
    EXPECT_NEAR(got.eigenvalue_condition / ref.eigenvalue_condition, 1.0, 0.1) << c.name;
    EXPECT_NEAR(got.eigenvalue_shift / ref.eigenvalue_shift, 1.0, 0.1) << c.name;
    EXPECT_EQ(got.eigenvalue_shift > kEigenvalueShiftWarning, c.warns) << c.name;
    EXPECT_EQ(ConditioningWarning(false, got).empty(), !c.warns) << c.name;
  }
  // The summary carries the sampled plant's numbers and the warning's rule.
  const ZWidth z(model::PhantomTable1(), T, 2);
  const DelaySummary s = z.Summarize();
  EXPECT_EQ(s.conditioning.eigenvalue_shift, z.sampled_plant().conditioning().eigenvalue_shift);
  EXPECT_TRUE(s.conditioning_warning.empty());
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

// Issue 31's done-when test: a seeded random sample of mode families (the
// generator below: sections uniform in [lo, hi], spacing ratio uniform in
// [1.01, 1.08], damping ratio log-uniform in [zeta_lo, 0.1], delay uniform in
// 0..20, first mode uniform in 150-600 rad/s, the last kept below 0.8 of
// Nyquist), each classified on a (K, B) grid by StableIntervals and by the
// independent brute force (long double referee where double disagrees).
struct RandomSample {
  uint64_t seed;
  int families, sections_lo, sections_hi;
  double zeta_lo;
  int num_b, min_points;
};

Tally ClassifyRandomFamilies(const RandomSample& r) {
  const double T = 1e-3;
  std::mt19937_64 rng(r.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Tally all;
  for (int f = 0; f < r.families; ++f) {
    const int n = r.sections_lo + static_cast<int>(u(rng) * (r.sections_hi - r.sections_lo + 1) * 0.999999);
    const double ratio = 1.01 + 0.07 * u(rng);
    const double zeta = r.zeta_lo * std::pow(0.1 / r.zeta_lo, u(rng));
    const int delay = static_cast<int>(u(rng) * 20.999);
    double w0 = 150.0 + 450.0 * u(rng);
    w0 = std::min(w0, 0.8 * std::numbers::pi / T / std::pow(ratio, n - 1));
    const model::Plant p = Family(n, w0, ratio, zeta);
    const ZWidth z(p, T, delay);
    const LoopBruteForce bf = IndependentBrute(p, delay, T);
    const LoopBruteForceT<long double> referee = IndependentBrute<long double>(p, delay, T);
    const double b_max = z.Summarize().B_max;
    ClassifyGrid g;
    g.b_top = std::isfinite(b_max) && b_max > 0 ? 1.1 * b_max : 0.1;
    g.num_b = r.num_b;
    g.min_points = r.min_points;
    g.points_inside = 2;
    const Tally t = Classify(z, [&](double K, double B) { return bf.MaxRoot(K, B); }, p, T, delay, g,
                             [&](double K, double B) { return referee.MaxRoot(K, B); });
    std::printf("family %d: %d sections, ratio %.4f, zeta %.3g, w0 %.1f, d %d, %s test: %ld points, %ld stable, "
                "%ld near a boundary, %ld refereed, %ld disagree\n", f, n, ratio, zeta, w0, delay,
                z.uses_polynomial_test() ? "Schur-Cohn" : "eigenvalue", t.points, t.stable, t.near_boundary,
                t.refereed, t.disagree);
    all.points += t.points;
    all.stable += t.stable;
    all.near_boundary += t.near_boundary;
    all.refereed += t.refereed;
    all.disagree += t.disagree;
  }
  std::printf("%d families: %ld points, %ld stable, %ld near a boundary, %ld refereed, %ld disagree\n", r.families,
              all.points, all.stable, all.near_boundary, all.refereed, all.disagree);
  return all;
}

#ifndef ZWIDTH_MANY_MODES
TEST(ZWidthExact, SeededRandomFamiliesAgreeWithIndependentEigenvalues) {
  const Tally t = ClassifyRandomFamilies({20261202, 12, 1, 16, 1e-4, 4, 40});
  EXPECT_EQ(t.disagree, 0);
  EXPECT_GT(t.stable, 0);
  EXPECT_LT(t.stable, t.points);
}

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
// 39 s (was 10.5 s with one false point, and 361 s). 64 sections 1 % apart
// at damping 1e-4 is tests/zwidth_corner_test.cc (delays 0, 2, 20): its
// ZWidth constructor took 65 s in the Hessenberg solves (the double state
// space's response off by 1e-3, B(theta) jagged: 23844 extrema on a
// 90559-point grid); with G_d in binary128 (stability/sampled_plant.cc) 0.7 s
// and 128 extrema. Its K_CR are ~1e-13, where the integrator's root lies
// 6e-14 inside the circle: neither the double brute force here nor its long
// double referee can classify the grid (its poles move by 3.4e-4 of their
// distance to the circle), so that test decides every point in 30 digits.
INSTANTIATE_TEST_SUITE_P(
    ManyModes, ZWidthFamilies,
    ::testing::Values(FamilyCase{"thirtytwo_sections_1pct_zeta1e3_d3", 32, 500, 1.01, 1e-3, 3, false},
                      FamilyCase{"sixtyfour_sections_8pct_zeta0025_d2", 64, 300, 1.08, 0.025, 2, false}),
    [](const ::testing::TestParamInfo<FamilyCase>& i) { return i.param.name; });

// The random sample's many-mode part: 3 seeded families of 17-64 sections
// (damping from 1e-3). 200 s wall, 91 s CPU under load 6 on 2 cores (it did
// not finish one family in 220 s before the pole-residue form was kept at many
// modes), nearly all of it in Summarize's scans of the O(n^3) eigenvalue
// test, hence the stress label.
TEST(ManyModesRandom, SeededFamiliesOf17To64SectionsAgreeWithIndependentEigenvalues) {
  const Tally t = ClassifyRandomFamilies({20261203, 3, 17, 64, 1e-3, 3, 30});
  EXPECT_EQ(t.disagree, 0);
  EXPECT_GT(t.stable, 0);
  EXPECT_LT(t.stable, t.points);
}
#endif

}  // namespace
}  // namespace zwidth::stability
