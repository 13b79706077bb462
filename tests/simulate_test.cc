// model/simulate.h: the simulated log against the convolution with the
// impulse response, and the torque's requested RMS.
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"

namespace zwidth {
namespace {

TEST(Simulate, NoiseFreeOutputIsTheConvolutionWithTheImpulseResponse) {
  const model::Plant p = model::PhantomTable1();
  model::SimulateOptions o;
  o.seconds = 0.5;
  o.encoder_step_rad = 0.0;
  o.delay_samples = 3;
  const model::SimulatedLog log = model::SimulateLog(p, o);
  // Impulse response h of G_d z^-3 from the state space.
  model::Plant pd = p;
  pd.delay_samples = 3;
  const model::StateSpace d = model::DiscretizeZoh(pd, 1e-3);
  std::vector<double> imp(log.torque.size(), 0.0);
  imp[0] = 1.0;
  const std::vector<double> h = model::SimulateDiscrete(d, imp);
  EXPECT_EQ(h[0], 0.0);
  EXPECT_EQ(h[3], 0.0);  // strictly proper after the delay
  for (size_t k = 0; k < log.torque.size(); k += 37) {
    double acc = 0;
    for (size_t j = 0; j <= k; ++j) acc += h[j] * log.torque[k - j];
    EXPECT_NEAR(log.position[k], acc, 1e-12 * (1 + std::abs(acc)));
  }
}

TEST(Simulate, TorqueHasTheRequestedRms) {
  const std::vector<double> u = model::BandLimitedNoise(30000, 1000, 300, 0.03, 5);
  double ss = 0;
  for (double v : u) ss += v * v;
  EXPECT_NEAR(std::sqrt(ss / u.size()), 0.03, 1e-12);
}

}  // namespace
}  // namespace zwidth
