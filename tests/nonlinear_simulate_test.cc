// The stick-slip simulation (model/nonlinear_simulate.h) against closed forms
// of a rigid body with Coulomb friction, against SimulateLog without friction,
// and against an independent fine-step integration with a Karnopp stick band.
#include "model/nonlinear_simulate.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "model/error.h"
#include "model/simulate.h"
#include "model/state_space.h"
#include "tests/karnopp_reference.h"

namespace zwidth::model {
namespace {

constexpr double kT = 1e-3;

Plant RigidBody() { return Plant{1.168e-3, 5.84e-3, {}, 0, "rigid"}; }

TEST(NonlinearSimulate, WithoutFrictionIsSimulateLogSampleForSample) {
  SimulateOptions o;
  o.seconds = 2.0;
  o.noise_std_rad = 1e-5;
  o.delay_samples = 2;
  Plant p = PhantomTable1();
  p.delay_samples = 1;
  const SimulatedLog a = SimulateLog(p, o);
  const SimulatedLog b = SimulateNonlinearLog(p, o, Friction{}, Actuator{});
  ASSERT_EQ(a.position.size(), b.position.size());
  EXPECT_EQ(a.torque, b.torque);
  for (size_t i = 0; i < a.position.size(); ++i) ASSERT_EQ(a.position[i], b.position[i]) << i;
}

TEST(NonlinearSimulate, ActuatorLimitsActOnTheTorqueBeforeThePlant) {
  SimulateOptions o;
  o.seconds = 1.0;
  o.encoder_step_rad = 0.0;
  const Actuator act{0.04, 0.005};
  const Plant p = PhantomTable1();
  const SimulatedLog b = SimulateNonlinearLog(p, o, Friction{}, act);
  std::vector<double> delivered = b.torque;
  for (double& u : delivered) {
    u = 0.005 * std::nearbyint(u / 0.005);  // written out here, not Actuator::Apply
    u = std::clamp(u, -0.04, 0.04);
  }
  const std::vector<double> y = SimulateDiscrete(DiscretizeZoh(p, kT), delivered);
  for (size_t i = 0; i < y.size(); ++i) ASSERT_NEAR(y[i], b.position[i], 1e-12 * (1 + std::abs(y[i]))) << i;
}

TEST(NonlinearSimulate, TorqueBelowBreakawayNeverMovesTheBody) {
  const Plant p = RigidBody();
  Friction f{0.01, 0.01, 0.0, 0.015, 0.015};
  StickSlipPlant s(ContinuousStateSpace(p), f, kT);
  for (double u : {0.005, 0.0149, -0.0149, 0.0125, 0.0}) {
    for (int k = 0; k < 100; ++k) s.Step(u);
    EXPECT_EQ(s.position(), 0.0) << u;
    EXPECT_EQ(s.phase(), SlipPhase::kStuck);
  }
  // An offset adds to the torque: 0.009 + 0.007 passes the breakaway level.
  Friction g = f;
  g.offset = 0.007;
  StickSlipPlant t(ContinuousStateSpace(p), g, kT);
  t.Step(0.009);
  EXPECT_GT(t.position(), 0.0);
  EXPECT_EQ(t.phase(), SlipPhase::kSlidingPos);
}

// m v' = u - Fc - b v from rest: v = (u - Fc)/b (1 - e^{-b t/m}),
// y = (u - Fc)/b (t - (m/b)(1 - e^{-b t/m})).
TEST(NonlinearSimulate, ConstantTorqueAboveBreakawayFollowsTheClosedForm) {
  const Plant p = RigidBody();
  const double m = p.m, b = p.b, fc = 0.012, u = 0.02;
  StickSlipPlant s(ContinuousStateSpace(p), Friction{fc, 0.004, 0.0, 0.018, 0.0}, kT);
  for (int k = 1; k <= 500; ++k) {
    s.Step(u);
    const double t = k * kT, e = 1.0 - std::exp(-b * t / m);
    const double y = (u - fc) / b * (t - m / b * e);
    ASSERT_NEAR(s.position(), y, 1e-11 * y) << k;
    ASSERT_NEAR(s.velocity(), (u - fc) / b * e, 1e-11 * (u - fc) / b * e) << k;
  }
  EXPECT_EQ(s.switches(), 1);
}

// Sliding with v0 > 0 and no torque: m v' = -Fc - b v stops at
// t_s = (m/b) ln(1 + b v0/Fc) after y_s = (m/b)(v0 + Fc/b)(1 - e^{-b t_s/m}) - Fc t_s/b,
// and stays there (no torque, no chattering). The friction's work is -Fc times the distance.
TEST(NonlinearSimulate, SlidingBodyStopsWhereAndWhenTheClosedFormSays) {
  const Plant p = RigidBody();
  const double m = p.m, b = p.b, fc = 0.01;
  StickSlipPlant s(ContinuousStateSpace(p), Friction::Symmetric(fc), kT);
  s.Step(0.3);  // one kick
  const double y1 = s.position(), v1 = s.velocity();
  const double e1 = 1.0 - std::exp(-b * kT / m);
  EXPECT_NEAR(v1, (0.3 - fc) / b * e1, 1e-11 * v1);
  const double ts = m / b * std::log(1.0 + b * v1 / fc);
  const double ys = y1 + m / b * (v1 + fc / b) * (1.0 - std::exp(-b * ts / m)) - fc * ts / b;
  const int stop_sample = static_cast<int>(std::ceil(ts / kT));
  for (int k = 0; k < stop_sample + 50; ++k) s.Step(0.0);
  EXPECT_NEAR(s.position(), ys, 1e-12 * ys);
  EXPECT_EQ(s.velocity(), 0.0);
  EXPECT_EQ(s.phase(), SlipPhase::kStuck);
  EXPECT_EQ(s.switches(), 2);
  EXPECT_NEAR(s.friction_work(), -fc * s.position(), 1e-12 * fc * s.position());
}

double MaxError(const std::vector<double>& a, const std::vector<double>& b) {
  double e = 0.0;
  for (size_t i = 0; i < a.size(); ++i) e = std::max(e, std::abs(a[i] - b[i]));
  return e;
}

TEST(NonlinearSimulate, FineStepKarnoppReferenceConvergesToIt) {
  for (const Plant& p : {RigidBody(), PhantomTable1()}) {
    const Friction f{0.008, 0.006, 0.001, 0.011, 0.0};
    const std::vector<double> u = BandLimitedNoise(1500, 1000.0, 30.0, 0.02, 7);
    StickSlipPlant s(ContinuousStateSpace(p), f, kT);
    std::vector<double> y(u.size());
    for (size_t k = 0; k < u.size(); ++k) {
      y[k] = s.position();
      s.Step(u[k]);
    }
    ASSERT_GT(s.switches(), 20) << p.name;  // stick-slip happened
    const double range = *std::max_element(y.begin(), y.end()) - *std::min_element(y.begin(), y.end());
    const double e1 = MaxError(KarnoppReference(p, f, u, kT, 30), y) / range;
    const double e2 = MaxError(KarnoppReference(p, f, u, kT, 300), y) / range;
    const double e3 = MaxError(KarnoppReference(p, f, u, kT, 3000), y) / range;
    std::printf("%s: switches %lld, Karnopp error / range at T/30 %.3g, T/300 %.3g, T/3000 %.3g\n",
                p.name.c_str(), static_cast<long long>(s.switches()), e1, e2, e3);
    EXPECT_LT(e2, 0.3 * e1) << p.name;
    EXPECT_LT(e3, 0.3 * e2) << p.name;
    EXPECT_LT(e3, 1e-3) << p.name;
  }
}

TEST(NonlinearSimulate, RefusesInvalidFrictionAndAPlantWithFeedthrough) {
  const StateSpace c = ContinuousStateSpace(RigidBody());
  EXPECT_THROW(StickSlipPlant s(c, Friction{-1.0, 0.0, 0.0, 0.0, 0.0}, kT), InputError);
  EXPECT_THROW(StickSlipPlant s(c, Friction::Symmetric(0.01), 0.0), InputError);
  StateSpace bad = c;
  bad.D = 1.0;
  EXPECT_THROW(StickSlipPlant s(bad, Friction::Symmetric(0.01), kT), InputError);
  SimulateOptions o;
  EXPECT_THROW(SimulateNonlinearLog(RigidBody(), o, Friction::Symmetric(0.01), Actuator{-1.0, 0.0}), InputError);
}

}  // namespace
}  // namespace zwidth::model
