// The plant with the user's hand (Hand, stability/loop_options.h) as one
// continuous state space; where the hand acts is described there. Its exact
// ZOH is model::DiscretizeZoh (model/state_space.h).
#pragma once

#include "model/plant.h"
#include "model/state_space.h"
#include "stability/loop_options.h"

namespace zwidth::stability {

// Continuous realisation of G / (1 + G Z_h) from the plant's (ContinuousStateSpace).
// G is strictly proper of relative degree 2 (C B = 0), so y'' = C A^2 x + g u_p
// with g = C A B; solving u_p = u - M y'' - B_h y' - K_h y for the plant input u_p:
//   u_p = (u - (M C A^2 + B_h C A + K_h C) x) / (1 + M g),
//   A_h = A - B (M C A^2 + B_h C A + K_h C) / (1 + M g),  B_h = B / (1 + M g).
// (g = 1/m times the product of the sections' high-frequency gains, > 0, so
// 1 + M g > 0 for M >= 0.) No polynomial is formed. Precondition: plant valid.
model::StateSpace ContinuousStateSpaceWithHand(const model::Plant& plant, const Hand& hand);

}  // namespace zwidth::stability
