// A closed-loop log for the tests of the joint (closed-loop) estimates: the
// plant (exact ZOH, 1 kHz) held by a PD loop, u = r - kp ym - kd (ym_k -
// ym_{k-1}) / T with kp = 5 N m/rad, kd = 0.02 N m s/rad, where ym = y + n is
// the measured position: n is white sensor noise plus a slow drift (a random
// walk), both fed back. r is white Gaussian torque (std::mt19937_64, seeded).
#pragma once

#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "model/state_space.h"

namespace zwidth {

struct ClosedLoopLog {
  std::vector<double> r, u, ym;
};

inline ClosedLoopLog SimulateClosedLoop(const model::Plant& p, double seconds, double r_rms, double noise_std,
                                 double drift_step, uint64_t seed) {
  const double T = 1e-3, kp = 5.0, kd = 0.02;
  const model::StateSpace d = model::DiscretizeZoh(p, T);
  EXPECT_EQ(d.D, 0.0);  // no feedthrough: no algebraic loop
  const size_t n = static_cast<size_t>(seconds / T);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  ClosedLoopLog log;
  log.r.resize(n);
  log.u.resize(n);
  log.ym.resize(n);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(d.A.rows());
  double drift = 0.0, prev = 0.0;
  for (size_t k = 0; k < n; ++k) {
    drift += drift_step * g(rng);
    const double y = d.C * x;
    const double ym = y + noise_std * g(rng) + drift;
    const double r = r_rms * g(rng);
    const double u = r - kp * ym - kd * (k ? (ym - prev) / T : 0.0);
    prev = ym;
    log.r[k] = r;
    log.u[k] = u;
    log.ym[k] = ym;
    x = d.A * x + d.B * u;
  }
  return log;
}

}  // namespace zwidth
