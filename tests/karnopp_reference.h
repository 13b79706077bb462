// A fine-step reference for the stick-slip simulation (model/nonlinear_simulate.h),
// independent of its switching logic: shared by tests/nonlinear_simulate_test.cc
// and bench/friction_benchmark.cc.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "model/friction.h"
#include "model/plant.h"
#include "model/state_space.h"

namespace zwidth::model {

// Independent reference: fine sub-steps h of the exact linear ZOH with the
// friction as a held input torque: sliding, -sign(v) Fc; inside the Karnopp
// band |v| < eps (eps ~ h), the torque that holds the body, clipped to the
// static band. Converges at O(h); the exact simulation must be its limit.
inline std::vector<double> KarnoppReference(const Plant& p, const Friction& f, const std::vector<double>& u, double kT,
                                            int sub) {
  const StateSpace c = ContinuousStateSpace(p);
  const StateSpace d = DiscretizeZoh(c, kT / sub);
  const Eigen::RowVectorXd CA = c.C * c.A, CA2 = CA * c.A;
  const double g = CA.dot(c.B);
  double u_max = 0.0;
  for (double v : u) u_max = std::max(u_max, std::abs(v));
  const double eps = 4.0 * g * (u_max + f.StaticPos() + f.StaticNeg()) * kT / sub;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(c.A.rows());
  std::vector<double> y(u.size());
  for (size_t k = 0; k < u.size(); ++k) {
    y[k] = c.C.dot(x);
    for (int j = 0; j < sub; ++j) {
      const double v = CA.dot(x);
      double fr;
      if (v > eps) {
        fr = -f.coulomb_pos;
      } else if (v < -eps) {
        fr = f.coulomb_neg;
      } else {
        const double need = -(u[k] + f.offset) - CA2.dot(x) / g - v / (g * kT / sub);
        fr = need < -f.StaticPos() ? -f.coulomb_pos : need > f.StaticNeg() ? f.coulomb_neg : need;
      }
      x = d.A * x + d.B * (u[k] + f.offset + fr);
    }
  }
  return y;
}

}  // namespace zwidth::model
