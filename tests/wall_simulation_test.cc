// The nonlinear wall (stability/wall_simulation.h) against the exact linear
// Z-width and an independent closed-loop simulation written here, and the
// friction predictions (stability/friction_prediction.h) against the wall.
#include "stability/wall_simulation.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "model/error.h"
#include "model/state_space.h"
#include "analysis/friction_amplitude.h"
#include "io/stability_files.h"
#include "stability/friction_prediction.h"
#include "stability/relay.h"
#include "stability/zwidth.h"

namespace zwidth::stability {
namespace {

constexpr double kT = 1e-3;

TEST(WallSimulation, WithoutNonlinearityFollowsTheExactZWidth) {
  const model::Plant p = model::PhantomTable1();
  for (int d : {1, 2, 4}) {
    for (double B : {0.0, 0.005}) {
      const double kcr = ZWidth(p, kT, d).At(B).K_cr;
      WallOptions o;
      o.delay_samples = d;
      o.damping = B;
      o.seconds = 20.0;
      o.stiffness = 0.9 * kcr;
      EXPECT_EQ(SimulateWall(p, o).outcome, WallOutcome::kDecays) << d << " " << B;
      o.stiffness = 1.1 * kcr;
      EXPECT_EQ(SimulateWall(p, o).outcome, WallOutcome::kGrows) << d << " " << B;
    }
  }
}

// Independent closed loop: the sampled plant with the delay as states,
// x' = A x + B u_{k-d}, u = -(K y + B (y - y_prev)/T), from rest at y0.
TEST(WallSimulation, LinearTraceEqualsTheSampledClosedLoop) {
  const model::Plant p = model::PhantomTable1();
  WallOptions o;
  o.delay_samples = 2;
  o.stiffness = 1.0;
  o.damping = 0.004;
  o.seconds = 0.5;
  o.initial_position = 0.02;
  const WallResult r = SimulateWall(p, o);
  const model::StateSpace d = model::DiscretizeZoh(p, kT);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(d.A.rows());
  x(d.A.rows() - 2) = p.m * o.initial_position;
  std::vector<double> u(r.position.size(), 0.0);
  double y_prev = o.initial_position, err = 0.0;
  for (size_t k = 0; k < r.position.size(); ++k) {
    const double y = d.C.dot(x);
    err = std::max(err, std::abs(y - r.position[k]));
    u[k] = -(o.stiffness * y + o.damping * (y - y_prev) / kT);
    y_prev = y;
    x = d.A * x + d.B * (k >= 2 ? u[k - 2] : 0.0);
  }
  EXPECT_LT(err, 1e-12);
}

TEST(WallSimulation, FrictionHoldsALinearlyUnstableWallAtSmallAmplitude) {
  const model::Plant p{1.168e-3, 5.84e-3, {}, 0, "rigid"};
  const double kcr = ZWidth(p, kT, 2).At(0.0).K_cr;
  WallOptions o;
  o.delay_samples = 2;
  o.stiffness = 1.2 * kcr;
  o.friction = model::Friction::Symmetric(0.005);
  o.initial_position = 0.02;
  EXPECT_EQ(SimulateWall(p, o).outcome, WallOutcome::kDecays);
  o.initial_position = 0.5;
  EXPECT_EQ(SimulateWall(p, o).outcome, WallOutcome::kGrows);
  o.initial_position = 0.02;
  o.friction = model::Friction{};
  EXPECT_EQ(SimulateWall(p, o).outcome, WallOutcome::kGrows);
}

// The relay on the stick-slip plant (continuous realisation, exact switching)
// with a friction of 1e-12 of the relay amplitude: the linear relay's answer.
TEST(RelayWithFriction, StickSlipPathWithNegligibleFrictionGivesTheLinearKcr) {
  const model::Plant p = model::PhantomTable1();
  RelayOptions o;
  o.delay_samples = 2;
  o.seconds = 10.0;
  const RelayResult lin = SimulateRelay(p, o);
  o.friction = model::Friction::Symmetric(1e-12 * o.amplitude);
  ASSERT_TRUE(o.Nonlinear());
  const RelayResult non = SimulateRelay(p, o);
  ASSERT_TRUE(lin.refined());
  ASSERT_TRUE(non.refined());
  EXPECT_NEAR(non.K_cr, lin.K_cr, 1e-6 * lin.K_cr);
  EXPECT_NEAR(non.f_cr_hz, lin.f_cr_hz, 1e-6 * lin.f_cr_hz);
  o.friction = model::Friction{};
  o.encoder_step = -1.0;
  EXPECT_THROW(SimulateRelay(p, o), InputError);
}

// Values past what any device renders are refused before the simulation
// (K = 1e300 ran and printed "grows (amplitude nan ...)" with exit 0).
TEST(WallSimulation, OptionsPastTheirRangesAreRefused) {
  auto problem = [](auto set) {
    WallOptions o;
    o.stiffness = 1.0;
    set(o);
    std::string why;
    return o.IsValid(&why) ? std::string("valid") : why;
  };
  EXPECT_EQ(problem([](WallOptions&) {}), "valid");
  EXPECT_EQ(problem([](WallOptions& o) { o.stiffness = 1e12; o.damping = 1e12; o.initial_position = -1e6; }), "valid");
  EXPECT_NE(problem([](WallOptions& o) { o.stiffness = 1e300; }).find("WallOptions::stiffness"), std::string::npos);
  EXPECT_NE(problem([](WallOptions& o) { o.damping = 2e12; }).find("WallOptions::damping"), std::string::npos);
  EXPECT_NE(problem([](WallOptions& o) { o.initial_position = 1e300; }).find("WallOptions::initial_position"),
            std::string::npos);
  EXPECT_NE(problem([](WallOptions& o) { o.stiffness = std::nan(""); }).find("WallOptions::stiffness"), std::string::npos);
}

}  // namespace
}  // namespace zwidth::stability
