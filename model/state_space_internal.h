// Internals of model/state_space.cc shared with the other ZOH and eigenvalue
// code (model/nonlinear_simulate.cc, stability/closed_loop.cc,
// stability/sampled_plant.cc). Not installed.
#pragma once

#include <Eigen/Core>

namespace zwidth::model::internal {

// Diagonal scales (powers of two) that balance M: diag(s)^-1 M diag(s).
Eigen::VectorXd BalancingScales(const Eigen::MatrixXd& M);

}  // namespace zwidth::model::internal
