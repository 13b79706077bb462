// analysis/batch.h specs: the probability of meeting a bound from a unit's
// value and std against a seeded Monte Carlo of the same normal, the verdict's
// three bands, and the parser's refusals.
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "analysis/batch.h"
#include "model/error.h"

namespace zwidth::analysis {
namespace {

std::map<std::string, std::string> Row(double v, double sd) {
  char a[40], b[40];
  std::snprintf(a, sizeof a, "%.17g", v);
  std::snprintf(b, sizeof b, "%.17g", sd);
  return {{"status", "ok"}, {"d2_K_cr_max", a}, {"d2_K_cr_max_std", b}};
}

// The fraction of N(v, sd) draws that meet the spec: an estimate of P independent of erfc.
double MonteCarlo(double v, double sd, const BatchSpec& s) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(v, sd);
  int met = 0;
  const int draws = 200000;
  for (int i = 0; i < draws; ++i) {
    const double x = n(rng);
    met += s.at_least ? x >= s.bound : x <= s.bound;
  }
  return static_cast<double>(met) / draws;
}

TEST(BatchSpec, ProbabilityOfMeetingIsTheMonteCarloFractionOfTheUnitsNormal) {
  for (const char* text : {"d2_K_cr_max>=1.4", "d2_K_cr_max>=1.5", "d2_K_cr_max>=1.62", "d2_K_cr_max<=1.55"}) {
    const BatchSpec s = ParseBatchSpec(text, {2, 4});
    auto row = Row(1.5, 0.05);
    ApplySpecs({s}, &row);
    const double p = std::stod(row.at("p_min")), mc = MonteCarlo(1.5, 0.05, s);
    EXPECT_NEAR(p, mc, 4 * std::sqrt(mc * (1 - mc) / 200000) + 1e-6) << text;
  }
}

TEST(BatchSpec, VerdictIsPassMarginalOrFailByTheProbability) {
  auto verdict = [](const char* text, double v, double sd) {
    auto row = Row(v, sd);
    ApplySpecs({ParseBatchSpec(text, {2})}, &row);
    return row.at("verdict");
  };
  EXPECT_EQ(verdict("d2_K_cr_max>=1.0", 1.5, 0.1), "pass");      // 5 std above
  EXPECT_EQ(verdict("d2_K_cr_max>=1.45", 1.5, 0.1), "marginal"); // met, 0.5 std above: P = 0.69
  EXPECT_EQ(verdict("d2_K_cr_max>=1.55", 1.5, 0.1), "marginal"); // not met, within noise: P = 0.31
  EXPECT_EQ(verdict("d2_K_cr_max>=2.0", 1.5, 0.1), "fail");      // 5 std below
  EXPECT_EQ(verdict("d2_K_cr_max>=1.45", 1.5, std::nan("")), "pass");  // no std: by the value alone
  EXPECT_EQ(verdict("d2_K_cr_max<=1.45", 1.5, std::nan("")), "fail");
  auto err = std::map<std::string, std::string>{{"status", "input_error"}};
  ApplySpecs({ParseBatchSpec("m<=1", {2})}, &err);
  EXPECT_EQ(err.at("verdict"), "error");
  auto none = Row(1.5, 0.1);
  ApplySpecs({}, &none);
  EXPECT_EQ(none.count("verdict"), 0u);  // no specs: no verdict columns
}

TEST(BatchSpec, ParserRefusesWhatNoColumnHolds) {
  EXPECT_NO_THROW(ParseBatchSpec("mode2_omega >= 1e3", {2}));
  EXPECT_NO_THROW(ParseBatchSpec("d4_B_max_from_zero<=0.01", {4}));
  for (const char* bad : {"d8_K_cr_max>=1", "d2_K_cr_max_std<=1", "mass>=1", "m>1", "m>=x", "m>=nan", "m>=1<=2",
                          "mode0_omega>=1", "serial>=1"}) {
    EXPECT_THROW(ParseBatchSpec(bad, {2, 4}), InputError) << bad;
  }
}

}  // namespace
}  // namespace zwidth::analysis
