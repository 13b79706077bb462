// The fleet report's labels (report/fleet_report.cc): every axis in the
// units the table's values are in (the batch's `units` column: a linear
// stage in N/m and N s/m, not N m/rad), and tick labels that tell ticks
// apart on a narrow range far from 0. The table is built here by hand (a
// Table-I-like unit scattered by a seeded generator); the expected labels
// are model/units.h's, written out, and the ticks are read back from the SVG.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <regex>
#include <set>
#include <string>

#include "analysis/batch.h"
#include "analysis/population.h"
#include "io/batch_table.h"
#include "report/fleet_report.h"
#include "tests/test_util.h"

namespace zwidth::report {
namespace {

std::string Full(double v) { return test::TableCell(v); }

io::BatchTable Units(const std::string& units, int n) {
  std::mt19937_64 rng(20261204);
  std::normal_distribution<double> z(0.0, 1.0);
  io::BatchTable t;
  for (int i = 0; i < n; ++i) {
    std::map<std::string, std::string> r;
    r["serial"] = "SN" + std::to_string(i);
    r["status"] = "ok";
    r["verdict"] = "pass";
    r["units"] = units;
    r["sample_rate_hz"] = "1000";
    r["delay_samples"] = "0";
    r["modes"] = "1";
    r["m"] = Full(1.168e-3 * (1 + 0.02 * z(rng)));
    r["m_std"] = Full(1e-6);
    r["b"] = Full(5.84e-3 * (1 + 0.05 * z(rng)));
    r["b_std"] = Full(1e-4);
    // A narrow column far from 0: 330 +- 0.05 (3 digits would print "330" at every tick).
    r["mode1_omega"] = Full(479.0);
    r["mode1_c"] = Full(83.0);
    r["mode1_v"] = Full(330.0 + 0.05 * z(rng));
    r["mode1_d"] = Full(80.0);
    r["d2_K_cr_max"] = Full(40.0 * (1 + 0.03 * z(rng)));  // the region figure's frame: 2 x the medians
    r["d2_B_max_from_zero"] = Full(0.1 * (1 + 0.03 * z(rng)));
    r["fit_quality"] = "good";
    t.rows.push_back(r);
  }
  t.columns = analysis::BatchColumns(t.rows);
  return t;
}

std::string Html(const io::BatchTable& t) {
  analysis::BatchOptions o;
  o.run.delays = {2};
  return FleetHtml(t, analysis::AnalysePopulation(t), nullptr, o, "test");
}

TEST(FleetReport, AxesFollowTheTablesUnits) {
  const std::string linear = Html(Units("linear", 12)), rotary = Html(Units("rotary", 12));
  for (const char* label : {"B [N s/m]", "K_CR [N/m], delay 2", "m [kg]", "b [N s/m]", "mode1_v [rad/s]"}) {
    EXPECT_NE(linear.find(label), std::string::npos) << label;
  }
  EXPECT_EQ(linear.find("N m"), std::string::npos);  // no rotary unit anywhere on a linear fleet
  for (const char* label : {"B [N m s/rad]", "K_CR [N m/rad], delay 2", "m [kg m^2]", "b [N m s/rad]"}) {
    EXPECT_NE(rotary.find(label), std::string::npos) << label;
  }
  EXPECT_EQ(rotary.find("mix rotary and linear"), std::string::npos);
  io::BatchTable both = Units("rotary", 12);
  both.rows[3]["units"] = "linear";  // one unit of the other kind
  EXPECT_NE(Html(both).find("The units mix rotary and linear axes"), std::string::npos);
}

TEST(FleetReport, TicksOfANarrowRangeAreAllDifferentAndCountsAreWhole) {
  const std::string h = Html(Units("rotary", 40));
  // The histogram of mode1_v: its SVG is the one whose x label names it.
  const size_t label = h.find("mode1_v [rad/s]");
  ASSERT_NE(label, std::string::npos);
  const size_t begin = h.rfind("<svg", label), end = h.find("</svg>", label);
  const std::string svg = h.substr(begin, end - begin);
  const std::regex tick("<text x='[^']*' y='([^']*)' font-size='10' text-anchor='(middle|end)'>([^<]*)</text>");
  std::set<std::string> x_ticks;
  int x_count = 0;
  double bottom = 0;
  for (std::sregex_iterator it(svg.begin(), svg.end(), tick), e; it != e; ++it) bottom = std::max(bottom, std::stod((*it)[1]));
  for (std::sregex_iterator it(svg.begin(), svg.end(), tick), e; it != e; ++it) {
    const std::string text = (*it)[3];
    if (std::stod((*it)[1]) == bottom) {  // the x axis' row of ticks
      x_ticks.insert(text);
      ++x_count;
    } else {  // a count: a whole number of units
      const double v = std::stod(text);
      EXPECT_EQ(v, std::round(v)) << text;
    }
  }
  EXPECT_GE(x_count, 3);
  EXPECT_EQ(static_cast<int>(x_ticks.size()), x_count) << "two x ticks print alike";
}

}  // namespace
}  // namespace zwidth::report
