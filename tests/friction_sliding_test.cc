// fit/friction_sliding.cc: the friction fit's simulations against the rigid
// body's closed forms with Coulomb friction fc (tau = m / b, evaluated at the
// sample instants from t = 0, not interval by interval as the simulation
// steps): a constant torque above fc from rest, v = v_inf (1 - e^{-t/tau}),
// x = v_inf (t - tau (1 - e^{-t/tau})), v_inf = (U - fc) / b; a coasting body
// stopping at t_stop = tau ln(1 + b v0 / fc); a torque inside [-fc, fc] at rest
// never moving. And the collocated simulation (micro-steps, events placed by
// interpolation) on a plant without sections against the exact rigid body.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "fit/friction_sliding_internal.h"
#include "model/plant.h"

namespace zwidth::fit::internal {
namespace {

constexpr double kM = 2e-3, kB = 8e-3, kFs = 1000.0;

TEST(FrictionSliding, ConstantTorqueAboveFrictionFollowsTheClosedForm) {
  const double U = 0.05, fc = 0.02, tau = kM / kB, v_inf = (U - fc) / kB;
  const std::vector<double> u(500, U);
  const Sliding s = SimulateRigidBody(u, kFs, kM, kB, fc, 0.0, 0.0);
  for (size_t j = 0; j < u.size(); ++j) {
    const double t = j / kFs;
    const double x = v_inf * (t - tau * (1 - std::exp(-t / tau)));
    EXPECT_NEAR(s.position[j], x, 1e-12 * (1 + std::abs(x))) << j;
    EXPECT_DOUBLE_EQ(s.sign[j], 1.0) << j;
    EXPECT_DOUBLE_EQ(s.moving[j], 1.0) << j;
  }
}

TEST(FrictionSliding, CoastingBodyStopsWhereTheClosedFormSays) {
  const double fc = 0.01, v0 = 3.0, tau = kM / kB, v_inf = -fc / kB;
  const double t_stop = tau * std::log(1 + kB * v0 / fc);
  const double x_stop = v_inf * t_stop + (v0 - v_inf) * tau * (1 - std::exp(-t_stop / tau));
  const std::vector<double> u(400, 0.0);
  const Sliding s = SimulateRigidBody(u, kFs, kM, kB, fc, 0.0, v0);
  const size_t j_stop = static_cast<size_t>(std::floor(t_stop * kFs));
  ASSERT_LT(j_stop + 2, u.size());
  for (size_t j = 0; j < u.size(); ++j) {
    const double t = j / kFs;
    const double x = t < t_stop ? v_inf * t + (v0 - v_inf) * tau * (1 - std::exp(-t / tau)) : x_stop;
    EXPECT_NEAR(s.position[j], x, 1e-12 * (1 + std::abs(x))) << j;
    const double moving = j < j_stop ? 1.0 : j == j_stop ? t_stop * kFs - j_stop : 0.0;
    EXPECT_NEAR(s.moving[j], moving, 1e-9) << j;
    EXPECT_NEAR(s.sign[j], moving, 1e-9) << j;  // moving forward only
  }
}

TEST(FrictionSliding, TorqueWithinTheFrictionNeverMovesTheBodyAtRest) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> d(-0.019, 0.019);
  std::vector<double> u(300);
  for (double& v : u) v = d(rng);
  // The offset shifts the band: U + offset within [-fc, fc].
  const Sliding s = SimulateRigidBody(u, kFs, kM, kB, 0.025, 0.005, 0.0);
  for (size_t j = 0; j < u.size(); ++j) {
    EXPECT_EQ(s.position[j], 0.0);
    EXPECT_EQ(s.moving[j], 0.0);
    EXPECT_EQ(s.sign[j], 0.0);
  }
}

// Two implementations: the collocated simulation of a plant with no sections
// is the rigid body; its events are placed to ~1/256 sample (second order), so
// the positions agree to a small fraction of the travel.
TEST(FrictionSliding, CollocatedWithoutSectionsIsTheRigidBody) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 0.03);
  std::vector<double> u(3000);
  for (double& v : u) v = g(rng);
  const double fc = 0.015, offset = 0.002;
  model::Plant p;
  p.m = kM;
  p.b = kB;
  const Sliding a = SimulateRigidBody(u, kFs, kM, kB, fc, offset, 0.0);
  const Sliding c = SimulateCollocated(u, kFs, p, fc, offset);
  EXPECT_TRUE(c.position_is_encoder);
  double travel = 0.0, worst = 0.0, moving_diff = 0.0, moving = 0.0;
  for (size_t j = 0; j < u.size(); ++j) {
    travel = std::max(travel, std::abs(a.position[j]));
    worst = std::max(worst, std::abs(a.position[j] - c.position[j]));
    moving_diff += std::abs(a.moving[j] - c.moving[j]);
    moving += a.moving[j];
  }
  ASSERT_GT(moving, 0.2 * u.size());  // it sticks and slips
  ASSERT_LT(moving, 0.95 * u.size());
  EXPECT_LT(worst, 1e-3 * travel);
  EXPECT_LT(moving_diff, 1e-2 * moving);
}

}  // namespace
}  // namespace zwidth::fit::internal
