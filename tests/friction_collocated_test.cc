// The friction fit (fit/friction_fit.h) on logs of the library's own
// stick-slip simulator, model::SimulateNonlinearLog (model::StickSlipPlant:
// friction at the plant input opposing the COLLOCATED motor/encoder velocity
// v = C A x, the topology of `zwidth simulate --coulomb`), where
// tests/friction_sim.h (friction_fit_test, friction_stress_test) has it oppose
// the rigid body's velocity with the sections after it. The two differ only
// by the modes, so the truth is the simulated device (Table I) and its
// Coulomb level. Measured on the fit that assumed the rigid body's topology
// (2026-12-02), on SimulateNonlinearLog's logs of these seeds: F_c -32 %,
// -50 %, -84 % and b +11 %, +79 %, +413 % at 5, 13 and 25 % of the torque rms.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "fit/friction_fit.h"
#include "model/nonlinear_simulate.h"
#include "model/plant.h"
#include "model/simulate.h"

namespace zwidth::fit {
namespace {

struct Case {
  double coulomb_fraction;  // F_c / torque rms
  uint64_t seed;
};

struct Outcome {
  FrictionFitResult r;
  double fc_true;
};

Outcome Fit(const model::SimulatedLog& log, double fc_true) {
  FitOptions fo;
  fo.num_modes = 2;
  fo.delay_samples = 0;
  const FitResult lin = FitModel(ident::EstimateFrequencyResponse(log.torque, log.position, log.sample_rate_hz, {}), fo);
  EXPECT_EQ(lin.status, FitStatus::kConverged) << lin.message;
  return {FitFriction(log.torque, log.position, log.sample_rate_hz, lin, fo, FrictionFitOptions{}), fc_true};
}

// Issue 32's done-when on the library's simulator: F_c within 10 %, b within
// 4 std and 10 % of Table I's, the collocated topology chosen.
void ExpectTruth(const Outcome& o, const char* what, double fraction) {
  const model::Plant truth = model::PhantomTable1();
  const FrictionFitResult& r = o.r;
  ASSERT_EQ(r.status, FrictionFitStatus::kFitted) << r.message;
  const double fc = r.friction.coulomb_pos, b = r.fit.plant.b;
  std::printf("%s: F_c %2.0f %% of rms: F_c %.4g +- %.2g (%+.1f %%), b %.4g +- %.2g (%+.1f %%, %.1f std), m %+.2f %% | %s\n", what,
              100 * fraction, fc, r.friction_std.coulomb_pos, 100 * (fc / o.fc_true - 1), b, r.fit.std_errors.b,
              100 * (b / truth.b - 1), (b - truth.b) / r.fit.std_errors.b, 100 * (r.fit.plant.m / truth.m - 1), r.message.c_str());
  EXPECT_NEAR(fc / o.fc_true, 1.0, 0.10);
  EXPECT_NEAR(b / truth.b, 1.0, 0.10);
  EXPECT_LT(std::abs(b - truth.b), 4 * r.fit.std_errors.b);
  EXPECT_EQ(r.topology, FrictionTopology::kCollocated);
  EXPECT_LT(r.collocated_residual_rms, r.rigid_body_residual_rms);
}

class CollocatedFriction : public ::testing::TestWithParam<Case> {};

// A log as `zwidth simulate` makes it (0.03 N m rms, 300 Hz band, 40960
// counts, 30 s, Table I): SimulateNonlinearLog, one period per sample.
// Measured before the simulator's cells were bounded (2026-12-03: it missed
// reversals shorter than a cell), seed 31 at 5 % drifted 0.011 rad from the
// exact path and the fit returned F_c and b off the truth (see
// tests/stick_slip_reference_test.cc for the simulator against a brute force).
TEST_P(CollocatedFriction, FitRecoversCoulombAndDamping) {
  const Case c = GetParam();
  model::SimulateOptions so;
  so.seed = c.seed;
  const double fc_true = c.coulomb_fraction * so.torque_rms;
  ExpectTruth(Fit(model::SimulateNonlinearLog(model::PhantomTable1(), so, model::Friction::Symmetric(fc_true),
                                              model::Actuator{}),
                  fc_true),
              "simulate", c.coulomb_fraction);
}

std::string Name(const ::testing::TestParamInfo<Case>& i) {
  return "Coulomb" + std::to_string(static_cast<int>(std::lround(100 * i.param.coulomb_fraction))) + "Percent";
}

INSTANTIATE_TEST_SUITE_P(Levels, CollocatedFriction,
                         ::testing::Values(Case{0.05, 31}, Case{0.13, 32}, Case{0.25, 33}), Name);

TEST(FrictionTopology, NamesRoundTrip) {
  for (FrictionTopology t : {FrictionTopology::kRigidBody, FrictionTopology::kCollocated}) {
    FrictionTopology back = FrictionTopology::kRigidBody;
    EXPECT_TRUE(FrictionTopologyFromString(ToString(t), &back));
    EXPECT_EQ(back, t);
  }
  FrictionTopology x;
  EXPECT_FALSE(FrictionTopologyFromString("distal", &x));
}

}  // namespace
}  // namespace zwidth::fit
