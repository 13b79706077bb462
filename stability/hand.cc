#include "stability/hand.h"

#include <Eigen/Core>

namespace zwidth::stability {

model::StateSpace ContinuousStateSpaceWithHand(const model::Plant& plant, const Hand& hand) {
  model::StateSpace s = model::ContinuousStateSpace(plant);
  const Eigen::RowVectorXd CA = s.C * s.A;
  const Eigen::RowVectorXd CA2 = CA * s.A;
  const double g = CA.dot(s.B);  // y'' = C A^2 x + g u (C B = 0)
  const double den = 1.0 + hand.M * g;
  const Eigen::RowVectorXd F = hand.M * CA2 + hand.B * CA + hand.K * s.C;
  s.A -= s.B * F / den;
  s.B /= den;
  return s;
}

}  // namespace zwidth::stability
