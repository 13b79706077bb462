// analysis/population.h against independent references: the median and MAD
// by sorting in the test, the chi-square quantiles of a published table, and
// a seeded normal population of known covariance, whose robust covariance
// and distances must approach the exact Mahalanobis distance.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "analysis/population.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::analysis {
namespace {

std::string Full(double v) { return test::TableCell(v); }

io::BatchTable Table(const std::vector<Eigen::Vector2d>& x, const std::vector<double>& std_m = {}) {
  io::BatchTable t;
  t.columns = {"serial", "status", "modes", "m", "m_std", "b"};
  for (size_t i = 0; i < x.size(); ++i) {
    t.rows.push_back({{"serial", "u" + std::to_string(i)}, {"status", "ok"}, {"modes", "0"}, {"m", Full(x[i](0))},
                      {"m_std", i < std_m.size() ? Full(std_m[i]) : ""}, {"b", Full(x[i](1))}});
  }
  return t;
}

TEST(ChiSquareQuantile, MatchesThePublishedTableToOnePercent) {
  // NIST/SEMATECH e-Handbook, table 1.3.6.7.4 (upper critical values of chi-square).
  EXPECT_NEAR(ChiSquareQuantile(0.99, 5), 15.086, 0.01 * 15.086);
  EXPECT_NEAR(ChiSquareQuantile(0.999, 10), 29.588, 0.01 * 29.588);
  EXPECT_NEAR(ChiSquareQuantile(0.999, 18), 42.312, 0.01 * 42.312);
  EXPECT_NEAR(ChiSquareQuantile(0.95, 30), 43.773, 0.01 * 43.773);
}

TEST(Population, MedianAndMadAreThoseOfTheSortedValues) {
  std::mt19937_64 rng(5);
  std::lognormal_distribution<double> d(0.0, 0.3);
  std::vector<Eigen::Vector2d> x;
  for (int i = 0; i < 51; ++i) x.push_back({d(rng), d(rng)});
  io::BatchTable t = Table(x);
  t.rows[3]["status"] = "input_error";  // left out
  const Population p = AnalysePopulation(t);
  ASSERT_EQ(p.status, PopulationStatus::kOk) << p.message;
  std::vector<double> m;
  for (size_t i = 0; i < x.size(); ++i) if (i != 3) m.push_back(x[i](0));
  std::sort(m.begin(), m.end());
  const double med = 0.5 * (m[24] + m[25]);  // 50 values
  std::vector<double> dev;
  for (double v : m) dev.push_back(std::abs(v - med));
  std::sort(dev.begin(), dev.end());
  EXPECT_EQ(p.columns[0].column, "m");
  EXPECT_EQ(p.columns[0].units, 50u);
  EXPECT_DOUBLE_EQ(p.columns[0].median, med);
  EXPECT_NEAR(p.columns[0].mad_sigma, 1.482602218505602 * 0.5 * (dev[24] + dev[25]), 1e-15);
  EXPECT_FALSE(p.units[3].ok);
  EXPECT_EQ(PopulationTable(p).rows.size(), 3u);  // m, b, the threshold
}

// Correlated normal units (rho = 0.8): the robust distance of each unit approaches the exact
// (x - mu)^T Sigma^-1 (x - mu); about 0.1 % of clean units exceed the 0.999 quantile; a unit
// planted off the correlation (each value within 2.5 sigma alone) is an outlier, named by D^2.
TEST(Population, DistanceOfANormalPopulationApproachesTheExactMahalanobis) {
  Eigen::Matrix2d sigma;
  sigma << 4e-8, 0.8 * 2e-4 * 1e-3, 0.8 * 2e-4 * 1e-3, 1e-6;  // sd 2e-4 and 1e-3, rho 0.8
  const Eigen::Vector2d mu(1e-3, 6e-3);
  const Eigen::Matrix2d L = sigma.llt().matrixL();
  std::mt19937_64 rng(17);
  std::normal_distribution<double> n;
  std::vector<Eigen::Vector2d> x;
  for (int i = 0; i < 4000; ++i) x.push_back(mu + L * Eigen::Vector2d(n(rng), n(rng)));
  const Eigen::Vector2d planted = mu + Eigen::Vector2d(2.5 * 2e-4, -2.5 * 1e-3);  // against rho
  x.push_back(planted);
  const Population p = AnalysePopulation(Table(x));
  ASSERT_EQ(p.status, PopulationStatus::kOk);
  ASSERT_EQ(p.distance_columns.size(), 2u);
  const Eigen::Matrix2d inv = sigma.inverse();
  double worst = 0;
  size_t flagged = 0;
  for (size_t i = 0; i + 1 < x.size(); ++i) {
    const double exact = (x[i] - mu).dot(inv * (x[i] - mu));
    worst = std::max(worst, std::abs(p.units[i].distance2 - exact) / (1.0 + exact));
    flagged += p.units[i].outlier;
  }
  EXPECT_LT(worst, 0.15);         // relative, through the robust estimates of 4000 units
  EXPECT_LE(flagged, 12u);        // expected 4 (0.1 %)
  const PopulationUnit& u = p.units.back();
  EXPECT_NEAR(u.distance2, (planted - mu).dot(inv * (planted - mu)), 0.15 * u.distance2);
  EXPECT_TRUE(u.outlier);
  EXPECT_NE(u.reasons.find("robust Mahalanobis"), std::string::npos) << u.reasons;
}

// The unit's own variance adds to the population's (S + C_i): a unit 6 population sigma off but
// with an own std of 3 sigma is within its noise, the same unit measured exactly is an outlier.
TEST(Population, AUnitsOwnStdLowersItsDistanceByItsVariance) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n;
  std::vector<Eigen::Vector2d> x;
  for (int i = 0; i < 101; ++i) x.push_back({1.0 + 0.1 * n(rng), 2.0 + 0.1 * n(rng)});
  x.back() = {1.6, 2.0};
  std::vector<double> sd(x.size(), 0.0);
  const Population a = AnalysePopulation(Table(x, sd));
  sd.back() = 0.3;
  const Population b = AnalysePopulation(Table(x, sd));
  // The same population statistics; only the unit's own variance changes.
  EXPECT_GT(a.units.back().distance2, b.units.back().distance2);
  EXPECT_TRUE(a.units.back().outlier);
  EXPECT_FALSE(b.units.back().outlier) << b.units.back().reasons;  // 6 sigma off, within its own noise
}

TEST(Population, FewUnitsOrBadOptionsAreSaidSo) {
  const Population p = AnalysePopulation(Table({{1, 2}, {1, 2}, {1, 2}}));
  EXPECT_EQ(p.status, PopulationStatus::kTooFewUnits);
  PopulationOptions o;
  o.outlier_quantile = 1.0;
  try {
    AnalysePopulation(Table({}), o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("PopulationOptions::outlier_quantile"), std::string::npos);
  }
}

TEST(Population, AnotherNumberOfModesIsAnOutlier) {
  std::vector<Eigen::Vector2d> x(20, Eigen::Vector2d(1.0, 2.0));
  for (size_t i = 0; i < x.size(); ++i) x[i] += Eigen::Vector2d(0.01 * i, 0.02 * ((i * 7) % 20));
  io::BatchTable t = Table(x);
  t.rows[4]["modes"] = "1";
  const Population p = AnalysePopulation(t);
  EXPECT_TRUE(p.units[4].outlier);
  EXPECT_NE(p.units[4].reasons.find("1 mode(s) where the population's median is 0"), std::string::npos) << p.units[4].reasons;
}

}  // namespace
}  // namespace zwidth::analysis
