// The robust method (ident/robust_frf.h) on periodic logs of the Table I
// plant driven by random-phase multisines (1..100 Hz, 1 Hz apart, 0.03 N m
// rms), simulated exactly with and without Coulomb friction
// (model::StickSlipPlant), with white sensor noise on the position.
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ident/robust_frf.h"
#include "model/error.h"
#include "model/nonlinear_simulate.h"
#include "model/plant.h"
#include "model/state_space.h"

namespace zwidth {
namespace {

constexpr int kPeriod = 1000;       // samples (1 s at 1 kHz: lines 1 Hz apart)
constexpr int kTransient = 3;       // periods dropped (the rigid body's m/b is 0.2 s)

// One realisation: P steady-state periods after kTransient, phases from `seed`.
ident::LocalRecord Realisation(double coulomb, double noise_std, int periods, uint64_t seed) {
  const model::Plant plant = model::PhantomTable1();
  model::StickSlipPlant sim(model::ContinuousStateSpace(plant), model::Friction::Symmetric(coulomb), 1e-3);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::normal_distribution<double> g(0.0, 1.0);
  const int lines = 100;
  const double a = 0.03 / std::sqrt(lines / 2.0);
  std::vector<double> period(kPeriod, 0.0);
  for (int k = 1; k <= lines; ++k) {
    const double ph = phase(rng);
    for (int t = 0; t < kPeriod; ++t) period[t] += a * std::cos(2.0 * std::numbers::pi * k * t / kPeriod + ph);
  }
  ident::LocalRecord r;
  for (int p = 0; p < kTransient + periods; ++p) {
    for (int t = 0; t < kPeriod; ++t) {
      const double y = sim.position() + noise_std * g(rng);
      sim.Step(period[t]);
      if (p < kTransient) continue;
      r.u.push_back(period[t]);
      r.y.push_back(y);
    }
  }
  return r;
}

ident::RobustEstimate Robust(double coulomb, int realisations, int periods) {
  std::vector<ident::LocalRecord> runs;
  for (int m = 0; m < realisations; ++m) runs.push_back(Realisation(coulomb, 1e-6, periods, 100 + m));
  return ident::EstimateRobust(runs, 1000.0, kPeriod);
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Coulomb friction (0.005 N m against 0.03 N m rms) makes the response depend
// on the phases: the nonlinear-distortion variance is well above the noise
// variance; the same device without friction shows no distortion above its
// noise (the difference total - noise is a chance fluctuation about 0).
TEST(RobustFrf, CoulombFrictionShowsDistortionAboveTheNoiseAndALinearDeviceDoesNot) {
  const ident::RobustEstimate friction = Robust(0.005, 4, 4), linear = Robust(0.0, 4, 4);
  ASSERT_EQ(friction.f_hz.size(), 100u);
  ASSERT_EQ(linear.f_hz.size(), 100u);
  std::vector<double> rf, rl;
  for (size_t l = 0; l < friction.f_hz.size(); ++l) {
    rf.push_back(friction.distortion_var[l] / friction.noise_var[l]);
    rl.push_back(linear.distortion_var[l] / linear.noise_var[l]);
  }
  EXPECT_GT(Median(rf), 10.0);
  EXPECT_LT(Median(rl), 1.0);
  // The linear device's best linear approximation is its sampled response.
  const model::DiscreteResponse exact(model::DiscretizeZoh(model::PhantomTable1(), 1e-3));
  for (size_t l = 0; l < linear.f_hz.size(); ++l) {
    const std::complex<double> gz = exact.AtTheta(2.0 * std::numbers::pi * linear.f_hz[l] / 1000.0);
    EXPECT_LT(std::abs(linear.H[l] - gz), 6.0 * std::sqrt(linear.noise_var[l]) + 1e-9 * std::abs(gz)) << linear.f_hz[l];
  }
}

// One realisation: the noise variance only.
TEST(RobustFrf, OneRealisationGivesTheNoiseVarianceOnly) {
  const ident::RobustEstimate e = Robust(0.0, 1, 3);
  EXPECT_EQ(e.num_realisations, 1);
  EXPECT_EQ(e.num_periods, 3);
  EXPECT_TRUE(std::isnan(e.distortion_var[0]));
  EXPECT_GT(e.noise_var[0], 0.0);
}

TEST(RobustFrf, OnePeriodIsRefusedWithWhatToDo) {
  const ident::LocalRecord r = Realisation(0.0, 1e-6, 1, 1);
  try {
    ident::EstimateRobust({r}, 1000.0, kPeriod);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace zwidth
