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

// A design's tolerances become bounds by their formulas: relative r around the design value x is
// [x (1 - r), x (1 + r)], absolute a is [x - a, x + a], min/max as given; a figure's value is the
// design's Z-width at that delay. Each side is a spec whose P is Phi of its own z (the p_ columns).
TEST(DesignSpecs, TolerancesAreBoundsAroundTheDesignsValues) {
  const std::string text = R"({"format": "zwidth-design",
 "model": {"m": 2e-3, "b": 0.01, "modes": [{"omega": 400, "c": 80, "v": 300, "d": 60}]},
 "tolerances": [
  {"parameter": "m", "relative": 0.1},
  {"parameter": "mode1_omega", "absolute": 25},
  {"parameter": "b", "max": 0.02},
  {"figure": "K_cr_max", "delay": 2, "relative": 0.2}]})";
  const io::Design d = io::ParseDesign(text, "d.json", ".");
  ReferenceStability z;
  z.delays = {2, 4};
  z.summaries.resize(2);
  z.summaries[0].K_cr_max = 30.0;
  const std::vector<BatchSpec> s = DesignSpecs(d, z);
  ASSERT_EQ(s.size(), 7u);  // two sides each but b (max only)
  auto bound = [&](const std::string& col, bool at_least) {
    for (const BatchSpec& x : s) if (x.column == col && x.at_least == at_least) return x.bound;
    ADD_FAILURE() << col;
    return 0.0;
  };
  EXPECT_DOUBLE_EQ(bound("m", true), 2e-3 * 0.9);
  EXPECT_DOUBLE_EQ(bound("m", false), 2e-3 * 1.1);
  EXPECT_DOUBLE_EQ(bound("mode1_omega", true), 375.0);
  EXPECT_DOUBLE_EQ(bound("mode1_omega", false), 425.0);
  EXPECT_DOUBLE_EQ(bound("b", false), 0.02);
  EXPECT_DOUBLE_EQ(bound("d2_K_cr_max", true), 24.0);
  EXPECT_DOUBLE_EQ(bound("d2_K_cr_max", false), 36.0);
  // A unit 1 std below the lower K_CR^max bound: P = Phi(-1) on that side, 1 - Phi(-13) on the other.
  auto row = Row(23.0, 1.0);
  row["m"] = "0.002", row["b"] = "0.01", row["mode1_omega"] = "400";
  ApplySpecs(s, &row);
  EXPECT_NEAR(std::stod(row.at("p_d2_K_cr_max_min")), 0.5 * std::erfc(1.0 / std::sqrt(2.0)), 1e-12);
  EXPECT_NEAR(std::stod(row.at("p_d2_K_cr_max_max")), 1.0, 1e-12);
  EXPECT_EQ(row.at("verdict"), "marginal");
  EXPECT_NE(row.at("verdict_reasons").find("d.json line 7, key 'tolerances[3]'"), std::string::npos) << row.at("verdict_reasons");
  // Judged again (a resumed row with another design): the old p_ columns go.
  ApplySpecs({ParseBatchSpec("m<=1", {2})}, &row);
  EXPECT_EQ(row.count("p_d2_K_cr_max_min"), 0u);
  EXPECT_EQ(row.at("verdict"), "pass");
}

TEST(DesignSpecs, ABrokenDesignIsRefusedNamingTheLineAndKey) {
  auto error = [](const std::string& text) {
    try {
      io::ParseDesign(text, "d.json", ".");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(error("{\"format\": \"zwidth-design\", \"model\": \"table1\",\n\"tolerances\": [\n{\"parameter\": \"m\", \"min\": 1},\n"
                  "{\"parameter\": \"b\",\n \"mx\": 1}]}").find("d.json line 5, key 'tolerances[1].mx'"),
            std::string::npos);
  EXPECT_NE(error("{\"format\": \"zwidth-design\", \"model\": \"table1\",\n\"tolerances\": [\n{\"parameter\": \"m\", \"min\": 1},\n"
                  "  {\"parameter\": \"m\", \"max\": 2}]}").find("line 4, key 'tolerances[1]': a second tolerance on m"),
            std::string::npos);
  EXPECT_NE(error("{\"format\": \"zwidth-design\", \"model\": \"table1\", \"tolerances\": "
                  "[{\"parameter\": \"b\", \"min\": 2, \"max\": 1}]}").find("max is below min"),
            std::string::npos);
  EXPECT_NE(error("{\"format\": \"model\", \"model\": \"table1\", \"tolerances\": []}").find("key 'format'"),
            std::string::npos);
  const io::Design d = io::ParseDesign(R"({"format": "zwidth-design", "model": "table1",
    "tolerances": [{"figure": "B_t", "delay": 8, "min": 0.001}, {"parameter": "mode3_c", "relative": 0.1}]})", "d.json", ".");
  ReferenceStability z;
  z.delays = {2};
  z.summaries.resize(1);
  EXPECT_THROW(DesignSpecs(d, z), InputError);  // delay 8 not run
}

}  // namespace
}  // namespace zwidth::analysis
