// The friction fit on the real EMPS log (../shared/real-data/EMPS, a linear
// axis in closed loop; input = force [N], output = motor position [m]),
// against the benchmark's reference IDIM-LS model: M = 95.1089 kg,
// Fv = 203.5034 N s/m, Fc = 20.3935 N, offset -3.1648 N (the benchmark's
// Main_EMPS reference values). Skipped where ../shared is absent.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "fit/friction_fit.h"
#include "io/log.h"

namespace zwidth::fit {
namespace {

const std::string kEmps = std::string(ZWIDTH_SOURCE_DIR) + "/../shared/real-data/EMPS/EMPS_train.csv";

TEST(EmpsFriction, RigidBodyAndCoulombWithinTenPercentOfTheReference) {
  if (!std::filesystem::exists(kEmps)) GTEST_SKIP() << kEmps << " not found";
  io::LogSelect sel;
  sel.input_column = "input";
  sel.output_column = "output";
  const io::Log log = io::ReadLog(kEmps, sel);
  const double fs = log.info.sample_rate_hz;
  ident::WelchOptions wo;
  FitOptions fo;
  fo.num_modes = 0;
  fo.band.fmin_hz = 2;
  fo.band.fmax_hz = 20;
  const FitResult lin = FitModel(ident::EstimateFrequencyResponse(log.input, log.output, fs, wo), fo);
  ASSERT_EQ(lin.status, FitStatus::kConverged);
  FrictionFitOptions o;
  o.welch = wo;
  const FrictionFitResult r = FitFriction(log.input, log.output, fs, lin, fo, o);
  std::printf("EMPS: linear-only M %.2f Fv %.1f; with friction M %.2f +- %.2f, Fv %.1f +- %.1f (IDIM %.1f +- %.1f), "
              "Fc %.2f +- %.2f, offset %.2f +- %.2f (%s)\n",
              lin.plant.m, lin.plant.b, r.fit.plant.m, r.fit.std_errors.m, r.fit.plant.b, r.fit.std_errors.b, r.idim_b,
              r.idim_b_std, r.friction.coulomb_pos, r.friction_std.coulomb_pos, r.friction.offset, r.friction_std.offset,
              ToString(r.status).c_str());
  EXPECT_TRUE(r.detected);
  EXPECT_EQ(r.status, FrictionFitStatus::kFitted);
  EXPECT_NEAR(r.fit.plant.m / 95.1089, 1.0, 0.10);
  EXPECT_NEAR(r.fit.plant.b / 203.5034, 1.0, 0.10);
  EXPECT_NEAR(r.friction.coulomb_pos / 20.3935, 1.0, 0.10);
}

}  // namespace
}  // namespace zwidth::fit
