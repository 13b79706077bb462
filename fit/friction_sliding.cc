#include "fit/friction_sliding_internal.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "model/state_space.h"

namespace zwidth::fit::internal {

Sliding SimulateRigidBody(const std::vector<double>& U, double fs, double m, double b, double fc, double offset,
                          double v0) {
  Sliding s{std::vector<double>(U.size()), std::vector<double>(U.size()), std::vector<double>(U.size()),
            std::vector<double>(U.size(), 0.0)};
  const double T = 1.0 / fs, tau = m / b;
  double v = v0, x = 0.0;
  for (size_t j = 0; j < U.size(); ++j) {
    s.position[j] = x;
    const double F = U[j] + offset;
    double left = T, sg = 0.0, mv = 0.0;
    while (left > 0) {
      if (v == 0.0 && std::abs(F) <= fc) break;  // stuck for the rest of the interval
      const double dir = v != 0.0 ? (v > 0 ? 1.0 : -1.0) : (F > 0 ? 1.0 : -1.0);
      const double v_inf = (F - fc * dir) / b;
      double dt = left;
      bool stops = false;
      if (v != 0.0 && v_inf * dir < 0.0) {
        const double t_stop = tau * std::log((v - v_inf) / (-v_inf));
        if (t_stop < left) { dt = t_stop; stops = true; }
      }
      const double e = std::exp(-dt / tau);
      x += v_inf * dt + (v - v_inf) * tau * (1.0 - e);
      v = stops ? 0.0 : v_inf + (v - v_inf) * e;
      sg += dir * dt;
      mv += dt;
      left -= dt;
    }
    s.sign[j] = sg / T;
    s.moving[j] = mv / T;
  }
  return s;
}

// The collocated topology (model/nonlinear_simulate.h, model::StickSlipPlant):
// the friction at the plant input opposes the encoder's velocity v = C A x,
// and while v = 0 it holds whatever torque keeps v at 0 (the plant then
// follows x' = (A - B C A^2 / g) x, g = C A B). Simulated from the measured
// torque on the realisation of (m, b, sections) by exact ZOH steps of 1/8
// sample; a step in which an event occurs (v reaching 0, the holding torque
// leaving [-F_c, F_c]) is walked again in 32 exact micro-steps, and the event
// inside its micro-step placed by linear interpolation, the rest of the
// micro-step advanced in the new phase by the same interpolation (events to
// 1/256 sample, second order: at 13 % friction on Table I, b -0.7 % and F_c
// +0.3 % at the truth's fixed point with 1/128 sample; one step of 1/8 with
// no walk, b -11 %, F_c +8 %, spurious sticking). Why not StickSlipPlant
// itself: its root finding costs ~0.4 s per 30 s log, and the fixed point
// needs tens of simulations. A velocity that touches 0 and turns back inside
// one step is not seen (StickSlipPlant checks for it). The averages per
// sample interval are those of SimulateRigidBody; position is y(jT).
Sliding SimulateCollocated(const std::vector<double>& U, double fs, const model::Plant& plant, double fc,
                           double offset) {
  constexpr int kSteps = 8, kMicroSteps = 32;
  const size_t n = U.size();
  Sliding s{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n), std::vector<double>(n)};
  s.position_is_encoder = true;
  model::Plant p = plant;
  p.delay_samples = 0;
  const model::StateSpace c = model::ContinuousStateSpace(p);
  const Eigen::RowVectorXd CA = c.C * c.A, CA2 = CA * c.A;
  const double g = CA.dot(c.B);
  model::StateSpace stuck = c;
  stuck.A = c.A - c.B * CA2 / g;
  stuck.B = Eigen::VectorXd::Zero(c.B.size());
  struct Grid {
    model::StateSpace moving, stuck;
    double dt;
  };
  const double h = 1.0 / (fs * kSteps);
  const Grid coarse{model::DiscretizeZoh(c, h), model::DiscretizeZoh(stuck, h), h};
  const Grid fine{model::DiscretizeZoh(c, h / kMicroSteps), model::DiscretizeZoh(stuck, h / kMicroSteps),
                  h / kMicroSteps};
  // The friction that holds the body at v = 0 under F: -F - C A^2 x / g.
  auto required = [&](const Eigen::VectorXd& z, double F) { return -F - CA2.dot(z) / g; };
  // The phase that follows v = 0 at z (as StickSlipPlant::Switch): 0 stuck, else the direction.
  auto after_stop = [&](const Eigen::VectorXd& z, double F) {
    const double f = required(z, F);
    return f < -fc ? 1 : (f > fc ? -1 : 0);
  };
  // One step of phase d from z into *out (no allocation: this runs 8-256
  // times a sample, and a returned vector's malloc/free took a quarter of
  // the friction fit's time).
  auto step = [&](const Grid& gr, int d, const Eigen::VectorXd& z, double F, Eigen::VectorXd* out) {
    if (d == 0) {
      out->noalias() = gr.stuck.A * z;
      return;
    }
    out->noalias() = gr.moving.A * z;
    *out += gr.moving.B * (F - fc * d);
  };
  // The event's fraction of the step from z0 to z1 in phase d, or -1 if none.
  auto event = [&](int d, const Eigen::VectorXd& z0, const Eigen::VectorXd& z1, double F) {
    if (d != 0) {
      const double v0 = CA.dot(z0), v1 = CA.dot(z1);
      if (d * v1 > 0.0) return -1.0;
      return d * v0 > 0.0 ? v0 / (v0 - v1) : 0.0;
    }
    const double f0 = required(z0, F), f1 = required(z1, F);
    if (std::abs(f1) <= fc) return -1.0;
    const double bound = f1 > fc ? fc : -fc;
    return std::abs(f1 - f0) > 0 ? std::clamp((bound - f0) / (f1 - f0), 0.0, 1.0) : 0.0;
  };
  double sg = 0.0, mv = 0.0, held = 0.0;
  // Time dt in phase d from z0 to z1: its share of the averages.
  auto account = [&](int d, const Eigen::VectorXd& z0, const Eigen::VectorXd& z1, double dt) {
    if (d != 0) {
      sg += d * dt;
      mv += dt;
    } else {
      held -= 0.5 * (CA2.dot(z0) + CA2.dot(z1)) / g * dt;
    }
  };
  Eigen::VectorXd x = Eigen::VectorXd::Zero(c.A.rows()), xn(x.size()), xe(x.size()), xs(x.size());
  int dir = 0;
  for (size_t j = 0; j < n; ++j) {
    s.position[j] = c.C.dot(x);
    const double F = U[j] + offset;
    sg = mv = held = 0.0;
    if (dir == 0) dir = after_stop(x, F);
    for (int k = 0; k < kSteps; ++k) {
      step(coarse, dir, x, F, &xn);
      if (event(dir, x, xn, F) < 0.0) {
        account(dir, x, xn, h);
        x.swap(xn);
        continue;
      }
      for (int q = 0; q < kMicroSteps; ++q) {
        step(fine, dir, x, F, &xn);
        const double theta = event(dir, x, xn, F);
        if (theta < 0.0) {
          account(dir, x, xn, fine.dt);
          x.swap(xn);
          continue;
        }
        xe = x + theta * (xn - x);
        account(dir, x, xe, theta * fine.dt);
        int next;
        if (dir != 0) {
          xe -= c.B * (CA.dot(xe) / g);  // v = 0 exactly (C B = 0: the position is kept)
          next = after_stop(xe, F);
        } else {
          next = required(xe, F) < 0.0 ? 1 : -1;
        }
        step(fine, next, xe, F, &xs);
        xn = xe + (1.0 - theta) * (xs - xe);
        account(next, xe, xn, (1.0 - theta) * fine.dt);
        x.swap(xn);
        dir = next;
      }
    }
    s.sign[j] = sg * fs;
    s.moving[j] = mv * fs;
    s.held[j] = held * fs;
  }
  return s;
}

}  // namespace zwidth::fit::internal
