// The fit's judgement of itself: order selection, the excited band, the
// quality verdict, short logs. Logs are simulated by SimulateLog (exact ZOH
// plant, band-limited white torque, encoder quantisation), seeded, 1 kHz.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "ident/welch.h"
#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"

namespace zwidth::fit {
namespace {

constexpr double kHz = 2 * std::numbers::pi;

ident::FrequencyResponse Frf(const Plant& p, uint64_t seed, double seconds = 30, double bandwidth_hz = 450) {
  SimulateOptions so;
  so.seed = seed;
  so.seconds = seconds;
  so.bandwidth_hz = bandwidth_hz;
  so.torque_rms = 0.03 * p.m / 1.168e-3;  // the encoder's resolution weighs alike
  const SimulatedLog log = SimulateLog(p, so);
  return ident::EstimateFrequencyResponse(log.torque, log.position, so.sample_rate_hz, ident::WelchOptions{});
}

// Rigid body of Table I plus sections at the given pole frequencies [Hz], each
// zero 15 % below its pole, damping ratios 0.05 (poles) and 0.04 (zeros).
Plant Device(const std::vector<double>& poles_hz) {
  Plant p = PhantomTable1();
  p.modes.clear();
  for (double f : poles_hz) p.modes.push_back({kHz * f, 2 * 0.05 * kHz * f, kHz * 0.85 * f, 2 * 0.04 * kHz * 0.85 * f});
  return p;
}

const std::vector<double> kPoles[] = {{}, {120}, {60, 210}, {50, 130, 290}};

class AutoOrder : public ::testing::TestWithParam<int> {};

TEST_P(AutoOrder, PicksTheTrueNumberOfModes) {
  const int n = GetParam();
  for (uint64_t seed : {11u, 12u}) {
    FitOptions o;
    o.auto_modes = true;
    const FitResult r = FitModel(Frf(Device(kPoles[n]), seed), o);
    ASSERT_EQ(r.status, FitStatus::kConverged);
    std::string table;
    for (const OrderTrial& t : r.order_table) {
      table += "\n" + std::to_string(t.num_modes) + " chi2/dof " + std::to_string(t.chi2_per_dof) + " BIC " +
               std::to_string(t.bic) + " poles";
      for (double f : t.pole_hz) table += " " + std::to_string(f);
      for (const std::string& x : t.spurious) table += "; " + x;
    }
    EXPECT_EQ(static_cast<int>(r.plant.modes.size()), n) << r.order_choice << table;
    EXPECT_EQ(r.order_table.size(), 5u);  // 0..max_modes = 4
    EXPECT_EQ(r.quality, FitQuality::kGood) << (r.reasons.empty() ? "" : r.reasons[0].message);
    for (size_t i = 0; i < r.plant.modes.size(); ++i) {
      EXPECT_NEAR(r.plant.modes[i].omega / (kHz * kPoles[n][i]), 1.0, 0.02);
    }
  }
}
INSTANTIATE_TEST_SUITE_P(Fit, AutoOrder, ::testing::Values(0, 1, 2, 3),
                         [](const auto& info) { return std::to_string(info.param) + "Modes"; });

TEST(FitQuality, UnderFittedLogIsPoor) {
  FitOptions o;
  o.num_modes = 2;
  const FitResult r = FitModel(Frf(Device(kPoles[3]), 21), o);
  ASSERT_EQ(r.status, FitStatus::kConverged);
  EXPECT_EQ(r.quality, FitQuality::kPoor);
  bool chi2 = false;
  for (const auto& q : r.reasons) chi2 |= q.code == "chi2_per_dof";
  EXPECT_TRUE(chi2);
}

TEST(FitQuality, OneModeTooManyIsFlagged) {
  FitOptions o;
  o.num_modes = 3;
  const FitResult r = FitModel(Frf(Device(kPoles[2]), 22), o);
  ASSERT_EQ(r.status, FitStatus::kConverged);
  EXPECT_EQ(r.quality, FitQuality::kPoor);
  EXPECT_FALSE(SpuriousSections(r, o).empty());
}

TEST(FitQuality, OneSegmentLogIsRefusedUnlessAllowed) {
  const ident::FrequencyResponse frf = Frf(PhantomTable1(), 23, 5.0);  // 5 s < two 4096-sample windows
  ASSERT_EQ(frf.num_averages, 1);
  FitOptions o;
  try {
    FitModel(frf, o);
    ADD_FAILURE() << "a one-segment log was fitted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("WelchOptions::window_length"), std::string::npos) << m;
    EXPECT_NE(m.find("FitOptions::allow_few_averages"), std::string::npos) << m;
  }
  o.allow_few_averages = true;
  const FitResult r = FitModel(frf, o);
  EXPECT_EQ(r.quality, FitQuality::kPoor);
  bool few = false;
  for (const auto& q : r.reasons) few |= q.code == "few_averages";
  EXPECT_TRUE(few);
}

TEST(FitQuality, InputStoppingAtTenHertzIsFittedOnlyBelowIt) {
  // The torque is band-limited to 10 Hz (the simulator's windowed-sinc low
  // pass: -6 dB at 10 Hz, over 20 dB down by 12 Hz); above, the "response" is
  // encoder noise over nothing.
  const ident::FrequencyResponse frf = Frf(Device({}), 24, 60, 10.0);
  FitOptions o;
  o.num_modes = 0;
  const FitResult r = FitModel(frf, o);
  ASSERT_EQ(r.status, FitStatus::kConverged);
  EXPECT_LE(r.band.f_hi_hz, 12.0);
  EXPECT_GT(r.band.num_low_input, 1000);
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    if (frf.f_hz[k] > 12.0) EXPECT_EQ(r.band.used[k], 0) << frf.f_hz[k];
  }
  EXPECT_NEAR(r.plant.m / PhantomTable1().m, 1.0, 0.05);
}

TEST(FitQuality, BandLimitsApplyToAGivenResponse) {
  const ident::FrequencyResponse frf = Frf(Device(kPoles[1]), 25);
  FitOptions o;
  o.num_modes = 0;
  o.band.fmin_hz = 2;
  o.band.fmax_hz = 20;
  const FitResult r = FitModel(frf, o);
  EXPECT_GE(r.band.f_lo_hz, 2.0);
  EXPECT_LE(r.band.f_hi_hz, 20.0);
  EXPECT_EQ(r.num_residuals / 2, r.band.num_used);
}

TEST(FitQuality, SixSampleDelayIsFoundAutomatically) {
  SimulateOptions so;
  so.seed = 26;
  so.delay_samples = 6;
  const SimulatedLog log = SimulateLog(PhantomTable1(), so);
  const auto frf = ident::EstimateFrequencyResponse(log.torque, log.position, 1000, ident::WelchOptions{});
  FitOptions o;
  o.auto_delay = true;
  const FitResult r = FitModel(frf, o);
  EXPECT_EQ(r.plant.delay_samples, 6) << r.delay_choice;
  EXPECT_EQ(r.quality, FitQuality::kGood) << (r.reasons.empty() ? "" : r.reasons[0].message);
  EXPECT_FALSE(r.delay_choice.empty());
}

TEST(FitQuality, SectionsAreNamedFromOneInCanonicalOrder) {
  FitResult r;
  r.plant = Device({100, 200});
  r.plant.modes[1].v = r.plant.modes[1].omega;  // section 2's pole cancelled by its zero
  r.plant.modes[1].d = r.plant.modes[1].c;
  r.std_errors = r.plant;
  for (Mode& m : r.std_errors.modes) m = {1, 1, 1, 1};
  const auto s = SpuriousSections(r, FitOptions{});
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].rfind("section 2:", 0), 0u) << s[0];
}

}  // namespace
}  // namespace zwidth::fit
