// io/stability_files.h: the boundary CSV of real ZWidth rows (Table I,
// delays 2 and 6, B up to past B_max), read back by a CSV reader written here
// and compared with the rows it came from: one line per stable interval (one
// line with interval -1 and nan K where none), the per-B columns repeated on
// each interval line, every number to the digits the header promises, the
// friction columns only when a row has them; the JSON of summaries and
// intervals with NaN and inf as null; the delays' refusals.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io/stability_files.h"
#include "model/plant.h"
#include "stability/zwidth.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {

std::vector<std::map<std::string, std::string>> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream h(line);
  for (std::string n; std::getline(h, n, ',');) names.push_back(n);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::map<std::string, std::string> r;
    size_t i = 0;
    for (std::string v; std::getline(s, v, ','); ++i) r[i < names.size() ? names[i] : "extra"] = v;
    EXPECT_EQ(i, names.size()) << line;
    rows.push_back(r);
  }
  return rows;
}

double Num(const std::map<std::string, std::string>& r, const std::string& key) {
  const auto it = r.find(key);
  EXPECT_NE(it, r.end()) << key;
  return it == r.end() ? NAN : std::strtod(it->second.c_str(), nullptr);
}

// Equal to the digits written (15 significant), nan to nan, inf to inf.
void ExpectSameNumber(double got, double want, const std::string& what) {
  if (std::isnan(want)) EXPECT_TRUE(std::isnan(got)) << what;
  else if (std::isinf(want)) EXPECT_EQ(got, want) << what;
  else EXPECT_NEAR(got, want, 1e-14 * std::abs(want)) << what << " " << got << " vs " << want;
}

std::vector<BoundaryRow> Rows() {
  const model::Plant p = model::PhantomTable1();
  std::vector<BoundaryRow> rows;
  for (int d : {2, 6}) {
    const stability::ZWidth z(p, 1e-3, d);
    const double top = 1.3 * z.Summarize().B_max;
    for (int i = 0; i <= 12; ++i) {
      const stability::ZWidth::Row r = z.RowAt(top * i / 12.0);
      rows.push_back(BoundaryRow{d, r.point, r.intervals});
      rows.back().K_passive = 0.5 * r.point.K_cr;
    }
  }
  return rows;
}

TEST(StabilityFiles, BoundaryCsvReadsBackAsItsRows) {
  const test::TempDir dir("zwidth_stability_files_");
  const std::vector<BoundaryRow> rows = Rows();
  WriteBoundaryCsv(dir / "b.csv", rows);
  const auto csv = ReadCsv(dir / "b.csv");
  size_t line = 0, with_none = 0;
  for (const BoundaryRow& r : rows) {
    const size_t n = r.intervals.size();
    with_none += n == 0;
    for (size_t i = 0; i < std::max<size_t>(n, 1); ++i, ++line) {
      ASSERT_LT(line, csv.size());
      const auto& c = csv[line];
      const std::string at = "line " + std::to_string(line + 2);
      EXPECT_EQ(Num(c, "delay_samples"), r.delay_samples) << at;
      EXPECT_NEAR(Num(c, "B"), r.point.B, 1e-11 * std::abs(r.point.B)) << at;  // 12 digits
      EXPECT_EQ(Num(c, "interval"), n ? double(i) : -1.0) << at;
      EXPECT_EQ(Num(c, "num_intervals"), double(n)) << at;
      ExpectSameNumber(Num(c, "K_lo"), n ? r.intervals[i].K_lo : NAN, at + " K_lo");
      ExpectSameNumber(Num(c, "K_hi"), n ? r.intervals[i].K_hi : NAN, at + " K_hi");
      ExpectSameNumber(Num(c, "K_cr"), r.point.K_cr, at + " K_cr");
      ExpectSameNumber(Num(c, "f_cr_hz"), r.point.f_cr_hz, at + " f_cr_hz");
      ExpectSameNumber(Num(c, "K_passive"), r.K_passive, at + " K_passive");
      EXPECT_EQ(Num(c, "verified"), r.point.verified ? 1.0 : 0.0) << at;
      EXPECT_EQ(c.count("A_star"), 0u) << at;  // no friction in any row
    }
  }
  EXPECT_EQ(line, csv.size());
  EXPECT_GT(with_none, 0u);  // B past B_max was written too
  // With friction in one row, every line has the four friction columns.
  std::vector<BoundaryRow> f = rows;
  f[1].A_star_valid = 1;
  f[1].A_star = 0.0123;
  WriteBoundaryCsv(dir / "f.csv", f);
  const auto fc = ReadCsv(dir / "f.csv");
  ASSERT_EQ(fc.size(), csv.size());
  for (const auto& c : fc) EXPECT_EQ(c.count("A_star_valid"), 1u);
}

TEST(StabilityFiles, JsonWritesNanAndInfAsNull) {
  stability::DelaySummary s;
  s.K_cr_at_zero_B = 2.5;
  s.K_cr_max = std::numeric_limits<double>::infinity();
  const nlohmann::json j = SummaryToJson(s);
  EXPECT_EQ(j["K_cr_at_zero_B"].get<double>(), 2.5);
  EXPECT_TRUE(j["K_cr_max"].is_null());
  EXPECT_TRUE(j["B_t"].is_null());  // nan: not computed
  const nlohmann::json iv = IntervalsToJson({stability::KInterval{0.0, std::numeric_limits<double>::infinity(), NAN, NAN, true}});
  ASSERT_EQ(iv.size(), 1u);
  EXPECT_EQ(iv[0]["K_lo"].get<double>(), 0.0);
  EXPECT_TRUE(iv[0]["K_hi"].is_null());
  EXPECT_TRUE(NumberOrNull(NAN).is_null());
  EXPECT_EQ(NumberOrNull(-3.0).get<double>(), -3.0);
}

TEST(StabilityFiles, LoopDelaysAreCheckedAndAddedUp) {
  EXPECT_EQ(LoopDelaysProblem({0, 2, 40}, "--delays"), "");
  EXPECT_NE(LoopDelaysProblem({}, "--delays").find("--delays is empty"), std::string::npos);
  EXPECT_NE(LoopDelaysProblem({2, -1}, "--delays").find("--delays = -1"), std::string::npos);
  EXPECT_NE(LoopDelaysProblem({100000}, "delays").find("delays = 100000"), std::string::npos);
  EXPECT_EQ(DelayText(2, 1), "loop 2 + model 1 = 3 samples");
  nlohmann::json rec;
  AddDelays(&rec, 4, 1);
  EXPECT_EQ(rec["delay_samples"].get<int>(), 4);
  EXPECT_EQ(rec["model_delay_samples"].get<int>(), 1);
  EXPECT_EQ(rec["total_delay_samples"].get<int>(), 5);
}

}  // namespace
}  // namespace zwidth::io
