// Internals of fit/friction_fit.cc for the tests of its fixed point
// (tests/friction_fixed_point_test.cc). Not installed.
#pragma once

#include <vector>

#include "fit/friction_fit.h"
#include "model/plant.h"

namespace zwidth::fit::internal {

// One evaluation of the simulation-based IDIM's map G (friction_fit.cc,
// IdimRound) on a log: the body simulated from the torque with (b, F_c,
// offset) on `plant` in `topology`, then regressed over the band up to
// cutoff_hz; its estimates and the rows' own covariance (not the fixed
// point's). For tests of the fixed point FitFriction returns; not a fit.
struct IdimMapValue {
  double b = 0.0, coulomb = 0.0, offset = 0.0;
  double b_std = 0.0, coulomb_std = 0.0, b_coulomb_cov = 0.0, offset_std = 0.0;
};
IdimMapValue EvaluateIdimMap(const std::vector<double>& input, const std::vector<double>& output, double sample_rate_hz,
                             const model::Plant& plant, FrictionTopology topology, double cutoff_hz, double b,
                             double coulomb, double offset, double min_speed_fraction = 0.0);

}  // namespace zwidth::fit::internal
