// `zwidth check` as data (analysis/scene_check.h): the distance of each object
// to the nearest stable-interval end in units of that end's std, and the
// marginal status within 2 std. The reference std is a brute force written
// here: K_cr recomputed by ZWidth::At on the plant with each log parameter
// moved by +-1e-4 (central differences, stability::PerturbLog), then
// J Sigma J^T; nothing of the implicit differentiation that KcrStd uses.
#include <cmath>
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

}  // namespace
}  // namespace zwidth::analysis
