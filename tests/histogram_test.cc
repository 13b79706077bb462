// report/histogram.h: the fleet report's bins over a robust range. A seeded
// population with one unit at 1000 x spreads over the bins (the old min-max
// range put every other unit in one bin) and the wild unit is counted beyond
// the edge; counts checked against a brute-force recount written here, the
// range against the population's own median and MAD computed here by sorting.
#include "report/histogram.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/batch.h"
#include "analysis/population.h"
#include "io/batch_table.h"
#include "model/error.h"
#include "report/fleet_report.h"

namespace zwidth::report {
namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
double MadSigma(const std::vector<double>& v) {
  const double m = Median(v);
  std::vector<double> d;
  for (double x : v) d.push_back(std::abs(x - m));
  return 1.4826 * Median(d);
}

// 199 units of m ~ N(1.2e-4, (6e-6)^2), seed 5, and one at 1000 x.
std::vector<double> PopulationWithOneWildUnit() {
  std::mt19937 rng(5);
  std::normal_distribution<double> m(1.2e-4, 6e-6);
  std::vector<double> v;
  for (int i = 0; i < 199; ++i) v.push_back(m(rng));
  v.push_back(1000 * 1.2e-4);
  return v;
}

TEST(RobustHistogram, OneUnitAt1000TimesIsCountedBeyondTheEdgeAndThePopulationSpreadsOverTheBins) {
  const std::vector<double> v = PopulationWithOneWildUnit();
  const double med = Median(v), s = MadSigma(v);
  const HistogramBins h = RobustHistogram(v, med, s, {});
  EXPECT_EQ(h.above, 1u);
  EXPECT_EQ(h.below, 0u);
  EXPECT_EQ(h.values, v.size());
  EXPECT_DOUBLE_EQ(h.max, 0.12);
  // The range: median +- 6 s clipped to the values, padded by 5 %.
  const double lo = std::max(*std::min_element(v.begin(), v.end()), med - 6 * s), hi = med + 6 * s;
  EXPECT_NEAR(h.lo, lo - 0.05 * (hi - lo), 1e-12 * hi);
  EXPECT_NEAR(h.hi, hi + 0.05 * (hi - lo), 1e-12 * hi);
  // Brute force: each bin's count from the range.
  ASSERT_EQ(h.counts.size(), 30u);
  const double w = (h.hi - h.lo) / 30;
  size_t binned = 0, occupied = 0, most = 0;
  for (size_t i = 0; i < 30; ++i) {
    size_t n = 0;
    for (double x : v) n += x >= h.lo + w * i && (i == 29 ? x <= h.hi : x < h.lo + w * (i + 1));
    EXPECT_EQ(h.counts[i], n) << "bin " << i;
    binned += h.counts[i];
    occupied += h.counts[i] > 0;
    most = std::max(most, h.counts[i]);
  }
  EXPECT_EQ(binned + h.below + h.above, v.size());
  // Not squashed: the 199 units cover many bins, none holds a quarter of them (the min-max range
  // of the old report put 199 of 200 in its first bin).
  EXPECT_GE(occupied, 12u);
  EXPECT_LT(most, 50u);
  // The old range for contrast (min to max, 30 bins): the first bin holds the 199.
  const double vmin = *std::min_element(v.begin(), v.end()), old_w = (0.12 - vmin) / 30;
  EXPECT_EQ(std::count_if(v.begin(), v.end(), [&](double x) { return x < vmin + old_w; }), 199);
}

TEST(RobustHistogram, AZeroSpreadFallsBackToQuantilesAndMarksNearbyAreTakenIn) {
  // Modes: 2 for all but two units (1 and 3): MAD = 0, the 1st-99th percentiles are 2.
  std::vector<double> modes(100, 2.0);
  modes[0] = 1, modes[1] = 3;
  const HistogramBins h = RobustHistogram(modes, 2.0, 0.0, {});
  EXPECT_LT(h.lo, 2.0);
  EXPECT_GT(h.hi, 2.0);
  EXPECT_EQ(h.below + h.above + std::accumulate(h.counts.begin(), h.counts.end(), size_t{0}), 100u);
  // A spec's bound just beyond the population widens the range; one far off does not.
  std::mt19937 rng(2);
  std::normal_distribution<double> k(30, 1);
  std::vector<double> v;
  for (int i = 0; i < 50; ++i) v.push_back(k(rng));
  const double med = Median(v), s = MadSigma(v);
  const double bound = med - 4 * s;
  ASSERT_LT(bound, *std::min_element(v.begin(), v.end()));
  const HistogramBins near = RobustHistogram(v, med, s, {bound});
  EXPECT_LT(near.lo, bound);
  const HistogramBins far = RobustHistogram(v, med, s, {1e6});
  EXPECT_LT(far.hi, 100.0);
  EXPECT_EQ(far.above, 0u);
}

TEST(RobustHistogram, BadOptionsAndNoValuesAreInputErrorsNamingTheField) {
  HistogramOptions o;
  o.bins = 0;
  try {
    RobustHistogram({1.0}, 1.0, 0.1, {}, o);
    FAIL() << "accepted bins = 0";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("HistogramOptions::bins"), std::string::npos) << e.what();
  }
  EXPECT_THROW(RobustHistogram({std::nan("")}, 0, 0, {}), InputError);
  std::string why;
  EXPECT_TRUE(HistogramOptions{}.IsValid(&why)) << why;
}

TEST(FleetHtml, AWildUnitIsALabelledCountBeyondTheHistogramsEdge) {
  const std::vector<double> v = PopulationWithOneWildUnit();
  io::BatchTable t;
  t.columns = {"serial", "status", "m"};
  for (size_t i = 0; i < v.size(); ++i) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v[i]);
    t.rows.push_back({{"serial", "SN" + std::to_string(i)}, {"status", "ok"}, {"m", b}});
  }
  const analysis::Population pop = analysis::AnalysePopulation(t);
  analysis::BatchOptions o;
  o.run.delays = {};
  const std::string html = FleetHtml(t, pop, nullptr, o, "");
  EXPECT_NE(html.find("1 above &#9654;"), std::string::npos);
  EXPECT_NE(html.find("1 above it (max 0.12)"), std::string::npos);
  EXPECT_EQ(html.find(" below</text>"), std::string::npos);
}

}  // namespace
}  // namespace zwidth::report
