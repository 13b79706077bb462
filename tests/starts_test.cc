// fit/starts.cc: the fit's starting points against exact answers: the rigid
// body read from a response that is exactly 1/(m s^2 + b s) with the ZOH's
// half sample and the delay (the estimate's own model, so m and b come back
// to rounding); the peaks' prominences on piecewise-linear profiles whose
// prominences follow from the definition (the height above the higher of the
// two lowest points before higher ground).
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "fit/fit_internal.h"
#include "ident/welch.h"

namespace zwidth::fit::internal {
namespace {

TEST(Starts, RigidBodyFromItsExactLowBand) {
  for (int delay : {0, 3}) {
    const double m = 2.3e-3, b = 7.1e-3, T = 1e-3;
    ident::FrequencyResponse frf;
    frf.sample_rate_hz = 1.0 / T;
    for (double f = 1.0; f <= 300.0; f += 1.0) {
      const double w = 2 * std::numbers::pi * f;
      frf.f_hz.push_back(f);
      frf.H.push_back(std::polar(1.0, -w * T * (delay + 0.5)) / cd(-m * w * w, b * w));
      frf.coherence.push_back(1.0);
      frf.H_std.push_back(0.0);
    }
    const model::Plant p = EstimateRigid(frf, delay);
    EXPECT_NEAR(p.m, m, 1e-12 * m) << delay;
    EXPECT_NEAR(p.b, b, 1e-9 * b) << delay;
    EXPECT_TRUE(p.modes.empty());
  }
}

// Linear interpolation through (index, value) knots.
std::vector<double> Profile(const std::vector<std::pair<int, double>>& knots) {
  std::vector<double> v;
  for (size_t k = 0; k + 1 < knots.size(); ++k) {
    const auto [i0, v0] = knots[k];
    const auto [i1, v1] = knots[k + 1];
    for (int i = i0; i < i1; ++i) v.push_back(v0 + (v1 - v0) * (i - i0) / double(i1 - i0));
  }
  v.push_back(knots.back().second);
  return v;
}

TEST(Starts, PeaksAreOrderedByTheirProminence) {
  // Peaks at 10 (5), 20 (4, on the 5's shoulder: col 3), 40 (2.2, col 0.5 to the
  // left, 1 to the right: the higher col counts), 60 (6, the highest: its cols
  // are the lowest points on each side, 0 and 0.2).
  const std::vector<double> v = Profile({{0, 0.0}, {10, 5.0}, {15, 3.0}, {20, 4.0}, {30, 0.5}, {40, 2.2},
                                         {50, 1.0}, {60, 6.0}, {70, 0.2}});
  const std::vector<Extremum> p = Peaks(v);
  ASSERT_EQ(p.size(), 4u);
  const size_t at[4] = {60, 10, 40, 20};
  const double prom[4] = {6.0 - 0.2, 5.0 - 0.5, 2.2 - 1.0, 4.0 - 3.0};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(p[i].index, at[i]) << i;
    EXPECT_NEAR(p[i].prominence, prom[i], 1e-12) << i;
  }
  // No interior maximum: none; a plateau counts once, at its first sample.
  EXPECT_TRUE(Peaks({1.0, 2.0, 3.0}).empty());
  const std::vector<Extremum> flat = Peaks({0.0, 1.0, 1.0, 1.0, 0.0});
  ASSERT_EQ(flat.size(), 1u);
  EXPECT_EQ(flat[0].index, 1u);
  EXPECT_NEAR(flat[0].prominence, 1.0, 0.0);
}

}  // namespace
}  // namespace zwidth::fit::internal
