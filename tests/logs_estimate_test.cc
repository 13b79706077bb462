// analysis/logs_estimate.h: the response of one device from its logs, against
// independent references: two noise-free simulated logs of Table I (seeds 1
// and 2, written as CSV) give the exact ZOH response of the plant
// (model::DiscreteResponse) within 2 % at 95 % of the coherent bins, as one
// log does; the two runs' per-bin std is the scatter between them; the same
// samples given twice (the file again, or a copy) are refused; and the length
// rule of CheckLogLength from its statement (3 segments at 50 % overlap with
// the default window: 2 L samples; one window L when given).
#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/logs_estimate.h"
#include "io/log.h"
#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"
#include "tests/test_util.h"

namespace zwidth::analysis {
namespace {

std::string SimulatedCsv(const test::TempDir& dir, const std::string& name, uint64_t seed) {
  model::SimulateOptions so;
  so.seconds = 20.0;
  so.encoder_step_rad = 0.0;
  so.seed = seed;
  const model::SimulatedLog log = model::SimulateLog(model::PhantomTable1(), so);
  const std::string path = dir / name;
  io::WriteLog(path, log.sample_rate_hz, log.torque, log.position);
  return path;
}

// The 95th percentile of |H - G| / |G| over the bins above 1 Hz with coherence >= 0.99.
double Error95(const ident::FrequencyResponse& r, size_t* bins) {
  const model::DiscreteResponse exact(model::DiscretizeZoh(model::PhantomTable1(), 1e-3));
  std::vector<double> err;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] < 1 || r.coherence[k] < 0.99) continue;
    const std::complex<double> g = exact.AtTheta(2 * std::numbers::pi * r.f_hz[k] / 1000);
    err.push_back(std::abs(r.H[k] - g) / std::abs(g));
  }
  *bins = err.size();
  if (err.empty()) return INFINITY;
  std::sort(err.begin(), err.end());
  return err[err.size() * 95 / 100];
}

TEST(LogsEstimate, TwoSimulatedLogsGiveTheExactZohResponse) {
  const test::TempDir dir("zwidth_logs_estimate_");
  const std::string a = SimulatedCsv(dir, "a.csv", 1), b = SimulatedCsv(dir, "b.csv", 2);
  size_t bins = 0;
  const LogsEstimate one = EstimateFromLogs({a}, LogsEstimateOptions{});
  EXPECT_LT(Error95(one.response.frf, &bins), 0.02);
  EXPECT_GT(bins, 300u);
  std::vector<std::string> notes;
  const LogsEstimate two = EstimateFromLogs({a, b}, LogsEstimateOptions{}, [&](const std::string& l) { notes.push_back(l); });
  EXPECT_EQ(two.response.num_runs, 2);
  ASSERT_EQ(two.infos.size(), 2u);
  EXPECT_EQ(two.total_samples, 40000u);
  EXPECT_NEAR(two.response.frf.sample_rate_hz, 1000.0, 1e-9);
  EXPECT_LT(Error95(two.response.frf, &bins), 0.02);
  EXPECT_FALSE(notes.empty());
  // Whole records: one segment per run, the per-bin std from the scatter of
  // the two runs' responses, which is finite and positive where they differ.
  LogsEstimateOptions whole;
  whole.whole_record = true;
  const LogsEstimate w = EstimateFromLogs({a, b}, whole);
  size_t finite = 0;
  for (double s : w.response.frf.H_std) finite += std::isfinite(s) && s > 0;
  EXPECT_GT(finite, w.response.frf.H_std.size() / 2);
}

TEST(LogsEstimate, TheSameSamplesTwiceAreRefused) {
  const test::TempDir dir("zwidth_logs_estimate_");
  const std::string a = SimulatedCsv(dir, "a.csv", 1);
  const std::string copy = dir / "copy.csv";
  std::filesystem::copy_file(a, copy);
  for (const std::vector<std::string>& twice : {std::vector<std::string>{a, a}, std::vector<std::string>{a, copy}}) {
    try {
      EstimateFromLogs(twice, LogsEstimateOptions{});
      ADD_FAILURE() << twice[1] << " accepted";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(twice[1] + " holds the same samples as " + twice[0], 0), 0u) << m;
    }
  }
}

TEST(LogsEstimate, LengthRuleIsThreeHalfOverlappingSegmentsOrOneWindow) {
  ident::WelchOptions o;
  o.window_length = 512;
  EXPECT_NO_THROW(CheckLogLength(1024, 1000.0, o, true));   // 512 + 2 x 256
  EXPECT_THROW(CheckLogLength(1023, 1000.0, o, true), InputError);
  EXPECT_NO_THROW(CheckLogLength(512, 1000.0, o, false));   // one window
  EXPECT_THROW(CheckLogLength(511, 1000.0, o, false), InputError);
  try {
    CheckLogLength(1000, 1000.0, o, true);
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("1000 samples"), std::string::npos) << m;
    EXPECT_NE(m.find("at least 1024 samples"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace zwidth::analysis
