// Issue 24, item 1: a model fitted at one period and used at another. Its
// delay_samples counts samples of its own sample_period_s, so at another
// period T the C++ API (analysis::AnalysePlantStability) counts it as
// d T_m / T samples when that is whole (io::ResolveModelPeriod), and refuses
// a fraction. The reference is the same plant with the delay converted by
// hand, which takes no conversion path.
#include <gtest/gtest.h>

#include "analysis/plant_stability.h"
#include "io/reference_models.h"
#include "model/error.h"

namespace zwidth::analysis {
namespace {

io::ModelFile FittedAtOneMs(int delay_samples) {
  io::ModelFile m = io::Table1Model();
  m.plant.delay_samples = delay_samples;
  m.sample_period_s = 1e-3;
  return m;
}

double KcrAtZero(const io::ModelFile& m, double T, int d) {
  return AnalysePlantStability(m, T, {.delays = {d}}).summaries.at(0).K_cr_at_zero_B;
}

TEST(PeriodRule, DelayFittedAtOneMsCountsTwiceAtHalfAMs) {
  io::ModelFile by_hand = FittedAtOneMs(2);  // 1 sample of 1 ms = 2 samples of 0.5 ms
  by_hand.sample_period_s = 5e-4;
  const PlantStability converted = AnalysePlantStability(FittedAtOneMs(1), 5e-4, {.delays = {2}});
  EXPECT_EQ(converted.summaries.at(0).K_cr_at_zero_B, KcrAtZero(by_hand, 5e-4, 2));  // to the last digit
  EXPECT_NE(converted.period_note.find("2 samples at the period 0.0005 s"), std::string::npos)
      << converted.period_note;
  io::ModelFile unconverted = FittedAtOneMs(1);  // what the API computed before: 1 sample of 0.5 ms
  unconverted.sample_period_s.reset();
  const double wrong = KcrAtZero(unconverted, 5e-4, 2);
  EXPECT_GT(wrong / converted.summaries.at(0).K_cr_at_zero_B, 1.2);  // the 31.5 %
}

TEST(PeriodRule, SamePeriodOrNoDelayIsLeftAsItIs) {
  EXPECT_EQ(AnalysePlantStability(FittedAtOneMs(1), 1e-3, {.delays = {2}}).period_note, "");
  EXPECT_EQ(AnalysePlantStability(FittedAtOneMs(0), 5e-4, {.delays = {2}}).period_note, "");
}

TEST(PeriodRule, FractionOfASampleIsRefused) {
  // 1 sample of 1 ms at 0.4 ms is 2.5 samples.
  try {
    AnalysePlantStability(FittedAtOneMs(1), 4e-4, {.delays = {2}});
    FAIL() << "a delay of 2.5 samples was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2.5 samples"), std::string::npos) << e.what();
  }
}

TEST(PeriodRule, PeriodOutsideItsRangeIsRefusedNamingIt) {
  for (double T : {1000.0, 1e-9, -1e-3}) {
    try {
      AnalysePlantStability(FittedAtOneMs(1), T, {.delays = {2}});
      FAIL() << "period " << T << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("ModelPeriod::period_s"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace zwidth::analysis
