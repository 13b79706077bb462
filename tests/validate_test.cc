// analysis::Validate (`zwidth validate`): a model checked on a fresh log, as
// MATLAB's compare and resid. Logs from model::SimulateLog (white torque
// through the exact ZOH plant, 40960-count encoder), seeded; the wrong model
// is another device (m and the first mode moved); the initial-state estimate
// against an output made here with a known input offset and initial position.
#include <cmath>

#include <gtest/gtest.h>

#include "analysis/validate.h"
#include "model/error.h"
#include "model/simulate.h"
#include "model/state_space.h"

namespace zwidth {
namespace {

io::Log LogOf(const model::Plant& plant, uint64_t seed) {
  model::SimulateOptions o;
  o.seed = seed;
  const model::SimulatedLog s = model::SimulateLog(plant, o);
  io::Log log;
  log.info.sample_rate_hz = s.sample_rate_hz;
  log.info.num_samples = s.torque.size();
  log.input = s.torque;
  log.output = s.position;
  return log;
}

io::ModelFile FileOf(const model::Plant& p) {
  io::ModelFile mf;
  mf.plant = p;
  mf.sample_period_s = 1e-3;
  return mf;
}

TEST(Validate, TheRightModelIsGoodOnAFreshLog) {
  const model::Plant p = model::PhantomTable1();
  const analysis::ValidationResult r = analysis::Validate(FileOf(p), LogOf(p, 11));
  EXPECT_TRUE(r.good) << (r.reasons.empty() ? "" : r.reasons[0]);
  EXPECT_GT(r.chi2_per_dof, 0.6);
  EXPECT_LT(r.chi2_per_dof, r.chi2_limit);
  EXPECT_GT(r.fit_percent, 99.0);
  EXPECT_LE(r.cross_correlation_outside, 5);  // of 101 lags at 99 %
  EXPECT_EQ(r.residual_autocorrelation.size(), 51u);
  EXPECT_EQ(r.cross_correlation.size(), 101u);
  EXPECT_DOUBLE_EQ(r.residual_autocorrelation[0], 1.0);
}

TEST(Validate, AModelOfAnotherDeviceIsPoor) {
  const model::Plant p = model::PhantomTable1();
  model::Plant other = p;
  other.m *= 1.15;
  other.modes[0].omega *= 1.08;
  other.modes[0].v *= 1.08;
  const analysis::ValidationResult r = analysis::Validate(FileOf(other), LogOf(p, 12));
  EXPECT_FALSE(r.good);
  ASSERT_FALSE(r.reason_codes.empty());
  EXPECT_EQ(r.reason_codes[0], "response_misfit");
  EXPECT_GT(r.chi2_per_dof, 10 * r.chi2_limit);
  EXPECT_LT(r.fit_percent, analysis::Validate(FileOf(p), LogOf(p, 12)).fit_percent);
}

TEST(Validate, TheInitialPositionAndAnInputOffsetAreEstimated) {
  const model::Plant p = model::PhantomTable1();
  io::Log log = LogOf(p, 13);
  const double beta = 2e-3, y0 = 0.37;  // N m, rad
  std::vector<double> u = log.input;
  for (double& x : u) x += beta;
  const model::StateSpace sd = model::DiscretizeZoh(p, 1e-3);
  log.output = model::SimulateDiscrete(sd, u);
  for (double& y : log.output) y += y0;
  const analysis::ValidationResult r = analysis::Validate(FileOf(p), log);
  EXPECT_NEAR(r.input_offset, beta, 1e-9 * beta + 1e-12);
  EXPECT_GT(r.fit_percent, 99.9999);
  EXPECT_TRUE(r.good);
}

TEST(Validate, ShortLogsAndBadOptionsAreRefused) {
  const model::Plant p = model::PhantomTable1();
  io::Log log = LogOf(p, 14);
  log.input.resize(6000);
  log.output.resize(6000);
  EXPECT_THROW(analysis::Validate(FileOf(p), log), InputError);  // 2 Welch segments of 4096
  analysis::ValidateOptions o;
  o.max_lag = 0;
  EXPECT_THROW(analysis::Validate(FileOf(p), LogOf(p, 14), o), InputError);
  // A delay of a fraction of the log's sample: refused, not rounded.
  io::ModelFile mf = FileOf(p);
  mf.plant.delay_samples = 1;
  mf.sample_period_s = 1.5e-3;
  EXPECT_THROW(analysis::Validate(mf, LogOf(p, 14)), InputError);
}

}  // namespace
}  // namespace zwidth
