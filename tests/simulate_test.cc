// model/simulate.h: the simulated log against the convolution with the
// impulse response, and the torque's requested RMS.
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"

namespace zwidth {
namespace {

// The reference is not model/state_space.h's ZOH: eq. (1) as its cascade of
// ODEs (each section x'' + c x' + w^2 x = in, out = (w^2/v^2)(x'' + d x' + v^2 x);
// then m p'' + b p' = in), integrated by classical RK4 at T/400 with the
// torque held over each sample after the delay.
std::vector<double> Rk4Reference(const model::Plant& p, const std::vector<double>& torque, double T, int delay) {
  const size_t n = p.modes.size();
  using State = std::vector<double>;  // per section x, x'; then p, p'
  auto deriv = [&](const State& s, double u) {
    State ds(s.size());
    double in = u;
    for (size_t i = 0; i < n; ++i) {
      const model::Mode& m = p.modes[i];
      const double x = s[2 * i], xd = s[2 * i + 1];
      const double xdd = in - m.c * xd - m.omega * m.omega * x;
      ds[2 * i] = xd;
      ds[2 * i + 1] = xdd;
      in = m.omega * m.omega / (m.v * m.v) * (xdd + m.d * xd + m.v * m.v * x);
    }
    ds[2 * n] = s[2 * n + 1];
    ds[2 * n + 1] = (in - p.b * s[2 * n + 1]) / p.m;
    return ds;
  };
  State s(2 * n + 2, 0.0);
  constexpr int kSub = 400;
  const double h = T / kSub;
  std::vector<double> y(torque.size());
  for (size_t k = 0; k < torque.size(); ++k) {
    y[k] = s[2 * n];
    const long i = static_cast<long>(k) - delay;
    const double u = i >= 0 ? torque[static_cast<size_t>(i)] : 0.0;
    for (int j = 0; j < kSub; ++j) {
      auto axpy = [](const State& a, double c, const State& b) {
        State r = a;
        for (size_t q = 0; q < r.size(); ++q) r[q] += c * b[q];
        return r;
      };
      const State k1 = deriv(s, u), k2 = deriv(axpy(s, h / 2, k1), u), k3 = deriv(axpy(s, h / 2, k2), u),
                  k4 = deriv(axpy(s, h, k3), u);
      for (size_t q = 0; q < s.size(); ++q) s[q] += h / 6 * (k1[q] + 2 * k2[q] + 2 * k3[q] + k4[q]);
    }
  }
  return y;
}

TEST(Simulate, NoiseFreeOutputIsTheContinuousModelUnderAZeroOrderHold) {
  const model::Plant p = model::PhantomTable1();
  model::SimulateOptions o;
  o.seconds = 0.5;
  o.encoder_step_rad = 0.0;
  o.delay_samples = 3;
  const model::SimulatedLog log = model::SimulateLog(p, o);
  const std::vector<double> ref = Rk4Reference(p, log.torque, 1e-3, 3);
  double scale = 0;
  for (double v : ref) scale = std::max(scale, std::abs(v));
  ASSERT_GT(scale, 0.0);
  EXPECT_EQ(log.position[3], 0.0);  // nothing moves before the delayed first sample acts
  for (size_t k = 0; k < ref.size(); ++k) ASSERT_NEAR(log.position[k], ref[k], 1e-10 * scale) << "sample " << k;
}

TEST(Simulate, TorqueHasTheRequestedRms) {
  const std::vector<double> u = model::BandLimitedNoise(30000, 1000, 300, 0.03, 5);
  double ss = 0;
  for (double v : u) ss += v * v;
  EXPECT_NEAR(std::sqrt(ss / u.size()), 0.03, 1e-12);
}

}  // namespace
}  // namespace zwidth
