// The friction fit (fit/friction_fit.h) on logs of tests/friction_sim.h: an
// independent stick-slip simulator of eq. (1) devices with a quantised
// encoder (exact events at v = 0; see its header). The truth is the
// simulated device; K_CR(0) is compared through stability::ZWidth on both
// plants.
#include "fit/friction_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "model/plant.h"
#include "stability/zwidth.h"
#include "tests/friction_sim.h"

namespace zwidth::fit {
namespace {

// Table I's PHANToM with the b = 0.004 and a 1-sample input delay.
model::Plant Phantom() {
  model::Plant p = model::PhantomTable1();
  p.b = 0.004;
  p.delay_samples = 1;
  return p;
}

FitOptions LinearOptions() {
  FitOptions o;
  o.num_modes = 2;
  o.delay_samples = 1;
  return o;
}

struct Case {
  double coulomb_fraction;  // F_c / torque rms
  int counts;
  uint64_t seed;
  double seconds = 30.0;
};

struct Outcome {
  FitResult linear;
  FrictionFitResult friction;
  double fc_true;
};

Outcome RunCase(const Case& c, FrictionModel model) {
  testing::FrictionLogOptions so;
  so.coulomb = c.coulomb_fraction * so.torque_rms;
  so.counts_per_rev = c.counts;
  so.seed = c.seed;
  so.seconds = c.seconds;
  const testing::FrictionLog log = testing::SimulateFrictionLog(Phantom(), so);
  Outcome out;
  out.fc_true = so.coulomb;
  out.linear = FitModel(ident::EstimateFrequencyResponse(log.torque, log.position, so.sample_rate_hz, {}),
                        LinearOptions());
  FrictionFitOptions fo;
  fo.model = model;
  out.friction = FitFriction(log.torque, log.position, so.sample_rate_hz, out.linear, LinearOptions(), fo);
  return out;
}

double Kcr0(const model::Plant& p) { return stability::ZWidth(p, 1e-3, 2).Summarize().K_cr_at_zero_B; }

class FrictionFitCases : public ::testing::TestWithParam<Case> {};

// The done-when of issue 32: b and F_c within 10 %, K_CR(0) within 5 %.
TEST_P(FrictionFitCases, RecoversCoulombDampingAndKcr) {
  const Case c = GetParam();
  const Outcome o = RunCase(c, FrictionModel::kAuto);
  const model::Plant truth = Phantom();
  const FrictionFitResult& r = o.friction;
  ASSERT_EQ(r.status, FrictionFitStatus::kFitted) << r.message;
  const double kt = Kcr0(truth), kf = Kcr0(r.fit.plant), kl = Kcr0(o.linear.plant);
  std::printf("F_c %.0f %% of rms, %d counts: b %.4g +- %.2g (linear-only %.4g), F_c %.4g +- %.2g (true %.4g), "
              "K_CR(0) %.4g (true %.4g, linear-only %.4g)\n",
              100 * c.coulomb_fraction, c.counts, r.fit.plant.b, r.fit.std_errors.b, o.linear.plant.b,
              r.friction.coulomb_pos, r.friction_std.coulomb_pos, o.fc_true, kf, kt, kl);
  EXPECT_NEAR(r.fit.plant.b / truth.b, 1.0, 0.10);
  EXPECT_NEAR(r.friction.coulomb_pos / o.fc_true, 1.0, 0.10);
  EXPECT_NEAR(kf / kt, 1.0, 0.05);
}

// A linear-only fit of a friction log whose b is more than 3 std off is
// never `good`: the verdict carries the `friction` reason.
TEST_P(FrictionFitCases, LinearOnlyFitWithFrictionInflatedDampingIsPoor) {
  const Case c = GetParam();
  const Outcome o = RunCase(c, FrictionModel::kNone);
  const FitResult& lin = o.friction.fit;
  EXPECT_EQ(o.friction.status, FrictionFitStatus::kNotDetected);
  const bool off = std::abs(lin.plant.b - Phantom().b) > 3 * lin.std_errors.b;
  bool reason = false;
  for (const QualityReason& q : lin.reasons) reason |= q.code == "friction";
  if (off) EXPECT_EQ(lin.quality, FitQuality::kPoor) << "b " << lin.plant.b << " +- " << lin.std_errors.b;
  EXPECT_EQ(reason, o.friction.detected);
  EXPECT_TRUE(o.friction.detected);
}

std::string CaseName(const ::testing::TestParamInfo<Case>& i) {
  return "Coulomb" + std::to_string(static_cast<int>(std::lround(100 * i.param.coulomb_fraction))) + "PercentCounts" +
         std::to_string(i.param.counts);
}

INSTANTIATE_TEST_SUITE_P(Seeded, FrictionFitCases,
                         ::testing::Values(Case{0.02, 40960, 11}, Case{0.16, 4000, 12}, Case{0.16, 40960, 13},
                                           Case{0.23, 40960, 14}),
                         CaseName);

// 2 % friction on 4000 counts, 10 s: the coarse encoder's class of issue 32's
// Table I seed 5005, where the time-domain detection alone gave z 3.8 (not
// detected, the linear b +182 % passed as the answer). Before 2026-12-03 this
// log was not detected (kNotDetected with auto) and its linear b, +35 %, not
// flagged. K_CR(0) is not asked of a 10 s log here (measured +7 %: the
// sections of a short coarse log).
TEST(FrictionFit, WeakFrictionOnCoarseEncoderIsDetectedAndFitted) {
  const Case c{0.02, 4000, 15, 10.0};
  const Outcome none = RunCase(c, FrictionModel::kNone);
  EXPECT_TRUE(none.friction.detected) << "z " << none.friction.detection_time_domain_z << " (time domain), "
                                      << none.friction.detection_frequency_domain_z << " (frequency domain)";
  const FitResult& lin = none.friction.fit;
  if (std::abs(lin.plant.b - Phantom().b) > 3 * lin.std_errors.b) EXPECT_EQ(lin.quality, FitQuality::kPoor);
  const Outcome o = RunCase(c, FrictionModel::kAuto);
  ASSERT_EQ(o.friction.status, FrictionFitStatus::kFitted) << o.friction.message;
  EXPECT_NEAR(o.friction.fit.plant.b / Phantom().b, 1.0, 0.10);
  EXPECT_NEAR(o.friction.friction.coulomb_pos / o.fc_true, 1.0, 0.10);
}

// No friction: not detected, so `auto` keeps the linear fit, with no
// `friction` reason (the detection's false alarms).
TEST(FrictionFit, LinearDeviceIsNotFlagged) {
  for (int counts : {4000, 40960}) {
    for (uint64_t seed : {21, 22, 23}) {
      const Outcome o = RunCase({0.0, counts, seed}, FrictionModel::kAuto);
      EXPECT_FALSE(o.friction.detected) << counts << " counts, seed " << seed << ": F_c "
                                        << o.friction.detection_coulomb << " +- " << o.friction.detection_coulomb_std;
      EXPECT_EQ(o.friction.status, FrictionFitStatus::kNotDetected);
      for (const QualityReason& q : o.friction.fit.reasons) EXPECT_NE(q.code, "friction");
    }
  }
}

// The generator's stick-slip: with F_c above every torque sample the body
// never moves; with F_c = 0 it never sticks.
TEST(FrictionSim, SticksUnderLargeFrictionAndSlidesWithout) {
  testing::FrictionLogOptions so;
  so.seconds = 2;
  so.coulomb = 10 * so.torque_rms;
  const testing::FrictionLog stuck = testing::SimulateFrictionLog(Phantom(), so);
  EXPECT_EQ(stuck.moving_fraction, 0.0);
  so.coulomb = 0;
  EXPECT_GT(testing::SimulateFrictionLog(Phantom(), so).moving_fraction, 0.999);
}

}  // namespace
}  // namespace zwidth::fit
