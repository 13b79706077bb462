// A test-only simulator of eq. (1) devices with Coulomb friction and a
// quantised encoder, written apart from the library (model/simulate.h knows
// no friction, and a test should not check the library against itself).
//
// How a log is made (all seeded):
//   - torque u_k: white Gaussian, torque_rms, one value per sample period T,
//     held (ZOH) and applied delay_samples later: on [kT, (k+1)T) the motor
//     gives u_{k-d} (0 before the log starts);
//   - rigid body with friction, m x'' + b x' = u + offset + tau_f, with
//     tau_f = -F_c sign(x') while moving; at rest the body stays at rest while
//     |u + offset| <= F_c (no breakaway level above F_c). It is integrated
//     exactly, with events: over each sub-step the input is constant, so
//     v(t) = v_inf + (v0 - v_inf) e^{-t b/m}, v_inf = (u + offset - F_c dir) / b,
//     and the instant where v reaches 0 is solved in closed form; there the
//     body sticks or restarts in the direction of the net force. No sign() in a
//     fixed-step integrator, so no chattering;
//   - the sections of eq. (1) act on the rigid body's position (output
//     y = prod_i M_i(s) x, unit DC gain each), discretised by Tustin at the
//     sub-step rate (substeps per sample, default 16: at 1 kHz the warping of
//     a 100 Hz section is 2e-4 relative);
//   - the encoder: y rounded to a multiple of 2 pi / counts, on a grid shifted
//     by a seeded fraction of a count.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "model/plant.h"

namespace zwidth::testing {

struct FrictionLogOptions {
  double sample_rate_hz = 1000.0;
  double seconds = 30.0;
  double torque_rms = 0.05;   // [N m]
  double coulomb = 0.0;       // F_c [N m]
  double offset = 0.0;        // constant torque [N m]
  int counts_per_rev = 4000;  // encoder; 0 = no quantisation
  int delay_samples = 1;
  int substeps = 16;
  uint64_t seed = 1;
};

struct FrictionLog {
  std::vector<double> torque, position;  // u_k, encoder reading y_k = y(kT)
  std::vector<double> velocity;          // the rigid body's true v(kT), for the tests' checks
  double moving_fraction = 0.0;          // of the sub-steps that end with v != 0
};

namespace friction_sim_internal {

// One Tustin biquad of w^2 (s^2 + d s + v^2) / (v^2 (s^2 + c s + w^2)), DF-II transposed.
struct Biquad {
  double b0, b1, b2, a1, a2, z1 = 0, z2 = 0;
  Biquad(const model::Mode& md, double h) {
    const double K = 2.0 / h, g = md.omega * md.omega / (md.v * md.v);
    const double a0 = K * K + md.c * K + md.omega * md.omega;
    b0 = g * (K * K + md.d * K + md.v * md.v) / a0;
    b1 = g * (2 * md.v * md.v - 2 * K * K) / a0;
    b2 = g * (K * K - md.d * K + md.v * md.v) / a0;
    a1 = (2 * md.omega * md.omega - 2 * K * K) / a0;
    a2 = (K * K - md.c * K + md.omega * md.omega) / a0;
  }
  double Step(double x) {
    const double y = b0 * x + z1;
    z1 = b1 * x - a1 * y + z2;
    z2 = b2 * x - a2 * y;
    return y;
  }
};

// Advances the rigid body (x, v) by h under the constant force U = u + offset,
// exactly, stopping at every zero of v.
inline void Advance(double m, double b, double fc, double U, double h, double* x, double* v) {
  double left = h;
  while (left > 0) {
    if (*v == 0.0 && std::abs(U) <= fc) return;  // stuck for the rest of the sub-step
    const double dir = *v != 0.0 ? (*v > 0 ? 1.0 : -1.0) : (U > 0 ? 1.0 : -1.0);
    const double tau = m / b, v_inf = (U - fc * dir) / b;
    double dt = left;
    bool stops = false;
    if (*v != 0.0 && v_inf * dir < 0.0) {
      const double t_stop = tau * std::log((*v - v_inf) / (-v_inf));
      if (t_stop < left) { dt = t_stop; stops = true; }
    }
    const double e = std::exp(-dt / tau);
    *x += v_inf * dt + (*v - v_inf) * tau * (1.0 - e);
    *v = stops ? 0.0 : v_inf + (*v - v_inf) * e;
    left -= dt;
  }
}

}  // namespace friction_sim_internal

// The device of issue 32's sweeps: Table I with b = 0.004 N m s/rad (friction
// then dominates the damping) and a 1-sample input delay.
inline model::Plant IssueThirtyTwoDevice() {
  model::Plant p = model::PhantomTable1();
  p.b = 0.004;
  p.delay_samples = 1;
  return p;
}

inline FrictionLog SimulateFrictionLog(const model::Plant& p, const FrictionLogOptions& o) {
  namespace fi = friction_sim_internal;
  const size_t n = static_cast<size_t>(std::llround(o.seconds * o.sample_rate_hz));
  const double T = 1.0 / o.sample_rate_hz, h = T / o.substeps;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, o.torque_rms);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double step = o.counts_per_rev > 0 ? 2 * std::numbers::pi / o.counts_per_rev : 0.0;
  const double grid = uniform(rng) * step;
  std::vector<fi::Biquad> sections;
  for (const model::Mode& md : p.modes) sections.emplace_back(md, h);
  FrictionLog log;
  log.torque.resize(n);
  for (double& u : log.torque) u = normal(rng);
  log.position.resize(n);
  log.velocity.resize(n);
  double x = 0, v = 0, y = 0;
  size_t moving = 0;
  for (size_t k = 0; k < n; ++k) {
    log.position[k] = step > 0 ? grid + step * std::round((y - grid) / step) : y;
    log.velocity[k] = v;
    const double u = k >= static_cast<size_t>(o.delay_samples) ? log.torque[k - o.delay_samples] : 0.0;
    for (int s = 0; s < o.substeps; ++s) {
      fi::Advance(p.m, p.b, o.coulomb, u + o.offset, h, &x, &v);
      y = x;
      for (fi::Biquad& q : sections) y = q.Step(y);
      moving += v != 0.0;
    }
  }
  log.moving_fraction = static_cast<double>(moving) / (static_cast<double>(n) * o.substeps);
  return log;
}

}  // namespace zwidth::testing
