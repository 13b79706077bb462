// `zwidth check` as data (analysis/scene_check.h): the distance of each object
// to the nearest stable-interval end in units of that end's std, and the
// marginal status within 2 std. The reference std is a brute force written
// here: K_cr recomputed by ZWidth::At on the plant with each log parameter
// moved by +-1e-4 (central differences, stability::PerturbLog), then
// J Sigma J^T; nothing of the implicit differentiation that KcrStd uses.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/scene_check.h"
#include "model/error.h"
#include "model/plant.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {
namespace {

constexpr double kT = 1e-3;
constexpr int kDelay = 2;

// A diagonal log covariance: relative std 1 % on every parameter, 3 % on m.
std::vector<double> DiagonalCovariance(const model::Plant& p) {
  const int n = stability::NumLogParameters(p);
  std::vector<double> cov(n * n, 0.0);
  for (int i = 0; i < n; ++i) cov[i * n + i] = i == 0 ? 9e-4 : 1e-4;
  return cov;
}

double BruteForceKcrStd(const model::Plant& p, const std::vector<double>& cov, double B) {
  const int n = stability::NumLogParameters(p);
  const double h = 1e-4;
  std::vector<double> grad(n);
  for (int i = 0; i < n; ++i) {
    std::vector<double> dx(n, 0.0);
    dx[i] = h;
    const double up = stability::ZWidth(stability::PerturbLog(p, dx), kT, kDelay).At(B).K_cr;
    dx[i] = -h;
    const double dn = stability::ZWidth(stability::PerturbLog(p, dx), kT, kDelay).At(B).K_cr;
    grad[i] = (up - dn) / (2 * h);
  }
  double var = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) var += grad[i] * cov[i * n + j] * grad[j];
  }
  return std::sqrt(var);
}

TEST(SceneCheck, DistanceInStdMatchesABruteForceAndSetsTheStatus) {
  const model::Plant p = model::PhantomTable1();
  const std::vector<double> cov = DiagonalCovariance(p);
  const double B = 0.01;
  const double kcr = stability::ZWidth(p, kT, kDelay).At(B).K_cr;
  const double s = BruteForceKcrStd(p, cov, B);
  ASSERT_GT(s, 0.0);
  const std::vector<io::SceneObject> objs = {{"far_in", kcr - 5 * s, B}, {"near_in", kcr - 1.5 * s, B},
                                             {"near_out", kcr + 1.5 * s, B}, {"far_out", kcr + 5 * s, B}};
  const SceneCheck sc = CheckScene(p, cov, kT, kDelay, {stability::LoopOptions{}}, objs);
  ASSERT_TRUE(sc.has_std);
  ASSERT_EQ(sc.objects.size(), 4u);
  const double expected[] = {5, 1.5, -1.5, -5};
  const SceneStatus status[] = {SceneStatus::kStable, SceneStatus::kMarginal, SceneStatus::kMarginal,
                                SceneStatus::kUnstable};
  for (size_t i = 0; i < 4; ++i) {
    const ObjectCheck& c = sc.objects[i];
    EXPECT_NEAR(c.boundary_K, kcr, 1e-9 * kcr) << objs[i].name;
    EXPECT_NEAR(c.boundary_K_std / s, 1.0, 0.02) << objs[i].name;
    EXPECT_NEAR(c.sigmas_to_boundary, expected[i], 0.02 * std::abs(expected[i])) << objs[i].name;
    EXPECT_EQ(c.status, status[i]) << objs[i].name << ": " << ToString(c.status);
    EXPECT_EQ(c.verdict.stable, i < 2) << objs[i].name;
  }
  EXPECT_EQ(sc.num_unstable, 1);
  EXPECT_EQ(sc.num_marginal, 2);
  // A wider margin makes the far objects marginal too; 0 turns the status off.
  SceneCheckOptions wide;
  wide.marginal_sigmas = 6;
  EXPECT_EQ(CheckScene(p, cov, kT, kDelay, {stability::LoopOptions{}}, objs, wide).num_marginal, 4);
  SceneCheckOptions off;
  off.marginal_sigmas = 0;
  const SceneCheck none = CheckScene(p, cov, kT, kDelay, {stability::LoopOptions{}}, objs, off);
  EXPECT_EQ(none.num_marginal, 0);
  EXPECT_EQ(none.num_unstable, 2);
}

TEST(SceneCheck, WithoutACovarianceTheAnswerIsTheNominalOne) {
  const model::Plant p = model::PhantomTable1();
  const double kcr = stability::ZWidth(p, kT, kDelay).At(0.0).K_cr;
  const std::vector<io::SceneObject> objs = {{"in", 0.999 * kcr, 0.0}, {"out", 1.001 * kcr, 0.0}};
  const SceneCheck sc = CheckScene(p, {}, kT, kDelay, {stability::LoopOptions{}}, objs);
  EXPECT_FALSE(sc.has_std);
  EXPECT_EQ(sc.objects[0].status, SceneStatus::kStable);
  EXPECT_EQ(sc.objects[1].status, SceneStatus::kUnstable);
  EXPECT_TRUE(std::isnan(sc.objects[0].sigmas_to_boundary));
  EXPECT_NEAR(sc.objects[1].boundary_K, kcr, 1e-9 * kcr);
}

TEST(SceneCheck, OptionsAreCheckedNamingTheField) {
  SceneCheckOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why));
  o.marginal_sigmas = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("marginal_sigmas"), std::string::npos);
  EXPECT_THROW(CheckScene(model::PhantomTable1(), {}, kT, kDelay, {stability::LoopOptions{}}, {}, o), InputError);
}

// Issue 31, must-have 2: one stability test for every caller. On hard models
// (8 lightly damped sections crowded together, where Schur-Cohn once called
// stable loops unstable) every (K, B) of a grid gets the same answer from
// ZWidth::IsStable, from membership in StableIntervals(B) (and RowAt(B)'s),
// from `check` (CheckScene's verdict) and from the summary's K_cr(0), B_max
// and B_max_from_zero; the grid holds every interval end at (1 +- 1e-3) and
// (1 +- 1e-4) and B_max, B_max_from_zero at (1 +- 1e-3).
struct HardModel {
  const char* name;
  double ratio, zeta;
  int delay;
};

model::Plant Crowded(double ratio, double zeta) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < 8; ++i) {
    const double w = 300.0 * std::pow(ratio, i), v = 0.93 * w;
    p.modes.push_back({w, 2 * zeta * w, v, 2 * zeta * v});
  }
  return p;
}

bool InsideOne(const std::vector<stability::KInterval>& iv, double K) {
  for (const stability::KInterval& v : iv) {
    if ((K > v.K_lo || (K == 0.0 && v.K_lo == 0.0)) && K < v.K_hi) return true;
  }
  return false;
}

class OneStabilityTest : public ::testing::TestWithParam<HardModel> {};

TEST_P(OneStabilityTest, EveryCallerAgreesAtEveryPointOfAGrid) {
  const HardModel& c = GetParam();
  const model::Plant p = Crowded(c.ratio, c.zeta);
  const stability::ZWidth z(p, kT, c.delay);
  ASSERT_FALSE(z.uses_polynomial_test()) << "the model must be a hard one";
  const stability::DelaySummary s = z.Summarize();
  ASSERT_TRUE(std::isfinite(s.B_max) && s.B_max > 0.0);
  std::vector<double> Bs;
  for (int i = 0; i <= 10; ++i) Bs.push_back(1.1 * s.B_max * i / 10.0);
  for (double b : {s.B_max, s.B_max_from_zero}) {
    if (std::isfinite(b) && b > 0.0) { Bs.push_back(b * (1 - 1e-3)); Bs.push_back(b * (1 + 1e-3)); }
  }
  std::vector<io::SceneObject> objects;
  std::vector<std::vector<stability::KInterval>> ivs;
  long near_boundary = 0;
  for (double B : Bs) {
    const std::vector<stability::KInterval> iv = z.StableIntervals(B);
    // RowAt (the boundary table's row) gives the same intervals and K_CR.
    const stability::ZWidth::Row row = z.RowAt(B);
    ASSERT_EQ(row.intervals.size(), iv.size()) << B;
    double k_top = s.K_cr_at_zero_B;
    std::vector<double> Ks = {0.0};
    for (size_t i = 0; i < iv.size(); ++i) {
      EXPECT_EQ(row.intervals[i].K_lo, iv[i].K_lo) << B;
      EXPECT_EQ(row.intervals[i].K_hi, iv[i].K_hi) << B;
      for (double e : {iv[i].K_lo, iv[i].K_hi}) {
        if (!(e > 0.0 && std::isfinite(e))) continue;
        k_top = std::max(k_top, e);
        for (double r : {1e-3, 1e-4}) { Ks.push_back(e * (1 - r)); Ks.push_back(e * (1 + r)); }
        near_boundary += 4;
      }
    }
    // At(B): K_CR is the end of the interval from 0+, else 0.
    const double expected_kcr = !iv.empty() && iv[0].K_lo == 0.0 ? iv[0].K_hi : 0.0;
    EXPECT_EQ(z.At(B).K_cr, expected_kcr) << B;
    EXPECT_EQ(row.point.K_cr, expected_kcr) << B;
    for (int i = 0; i <= 24; ++i) Ks.push_back(2 * k_top * std::pow(1e-4, 1.0 - i / 24.0));
    for (double K : Ks) objects.push_back({"o", K, B});
    ivs.resize(objects.size(), iv);
  }
  const SceneCheck sc = CheckScene(p, {}, kT, c.delay, {stability::LoopOptions{}}, objects);
  ASSERT_EQ(sc.objects.size(), objects.size());
  long stable = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    const double K = objects[i].K, B = objects[i].B;
    const bool is = z.IsStable(K, B);
    stable += is;
    EXPECT_EQ(is, InsideOne(ivs[i], K)) << "is_stable vs stable_intervals at K = " << K << ", B = " << B;
    EXPECT_EQ(is, sc.objects[i].verdict.stable) << "is_stable vs check at K = " << K << ", B = " << B;
    // The summary: nothing stable past B_max; K -> 0+ stable exactly below B_max_from_zero.
    if (B > s.B_max) EXPECT_FALSE(is) << K << " " << B;
    if (K == 0.0) EXPECT_EQ(is, B < s.B_max_from_zero) << B;
    if (B == 0.0 && K > 0.0 && s.reopened_bands.empty() && ivs[i].size() == 1) {
      EXPECT_EQ(is, K < s.K_cr_at_zero_B) << K;
    }
  }
  std::printf("%s: %zu points, %ld stable, %ld within 1e-3 of an interval end\n", c.name, objects.size(), stable,
              near_boundary);
  EXPECT_GT(stable, 0);
  EXPECT_LT(stable, static_cast<long>(objects.size()));
}

INSTANTIATE_TEST_SUITE_P(Crowded, OneStabilityTest,
                         ::testing::Values(HardModel{"issue_8_sections_8pct_zeta0025_d2", 1.08, 0.025, 2},
                                           HardModel{"eight_sections_1pct_zeta1e3_d4", 1.01, 1e-3, 4}),
                         [](const ::testing::TestParamInfo<HardModel>& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace zwidth::analysis
