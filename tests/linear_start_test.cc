// fit/linear_start.cc: polynomial roots and their second-order factors against
// polynomials built from known roots, and the Sanathanan-Koerner start against
// the plant whose exact, noise-free ZOH response it is given.
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "fit/fit_internal.h"
#include "ident/welch.h"
#include "model/plant.h"
#include "model/state_space.h"

namespace zwidth::fit::internal {
namespace {

// sum a_i x^i from its roots (complex pairs given once, with their conjugates).
std::vector<double> FromRoots(const std::vector<cd>& roots) {
  std::vector<cd> p = {1.0};
  for (const cd& r : roots) {
    std::vector<cd> q(p.size() + 1, 0.0);
    for (size_t i = 0; i < p.size(); ++i) q[i + 1] += p[i], q[i] -= r * p[i];
    p = q;
  }
  std::vector<double> a;
  for (const cd& c : p) a.push_back(c.real());
  return a;
}

TEST(LinearStart, RootsAndQuadraticsOfKnownFactors) {
  // (s^2 + 2 zeta w s + w^2) for (w, zeta) = (3, 0.1), (0.7, 0.5), and real roots -2, -5.
  const double w1 = 3.0, z1 = 0.1, w2 = 0.7, z2 = 0.5;
  auto pair = [](double w, double z) { return cd(-z * w, w * std::sqrt(1 - z * z)); };
  const std::vector<cd> roots = {pair(w1, z1), std::conj(pair(w1, z1)), pair(w2, z2), std::conj(pair(w2, z2)), -2.0, -5.0};
  std::vector<double> a = FromRoots(roots);
  for (double& c : a) c *= 3.5;  // the leading coefficient does not matter
  const std::vector<cd> got = Roots(a);
  ASSERT_EQ(got.size(), roots.size());
  for (const cd& r : roots) {
    double best = 1e300;
    for (const cd& g : got) best = std::min(best, std::abs(g - r));
    EXPECT_LT(best, 1e-12 * std::abs(r)) << r;
  }
  std::vector<std::pair<double, double>> q = Quadratics(got);
  ASSERT_EQ(q.size(), 3u);
  std::sort(q.begin(), q.end());
  EXPECT_NEAR(q[0].first, w2, 1e-12);
  EXPECT_NEAR(q[0].second, 2 * z2 * w2, 1e-12);
  EXPECT_NEAR(q[1].first, w1, 1e-12);
  EXPECT_NEAR(q[1].second, 2 * z1 * w1, 1e-12);
  // The real roots -2 and -5 paired: s^2 + 7 s + 10, w = sqrt(10).
  EXPECT_NEAR(q[2].first, std::sqrt(10.0), 1e-12);
  EXPECT_NEAR(q[2].second, 7.0, 1e-12);
  EXPECT_TRUE(Roots({4.0}).empty());
}

// The exact ZOH response of Table I's model (2 sections) at 1 kHz: the linear
// start's sections within 3 % of the truth in frequency (the start only
// needs to land in the basin; the ZOH's half sample is taken out, not all of it).
TEST(LinearStart, NoiseFreeResponseGivesTheSectionsFrequencies) {
  const model::Plant truth = model::PhantomTable1();
  const double T = 1e-3;
  const model::DiscreteResponse r(model::DiscretizeZoh(truth, T));
  ident::FrequencyResponse frf;
  frf.sample_rate_hz = 1000.0;
  for (double f = 1.0; f <= 350.0; f += 1.0) {
    frf.f_hz.push_back(f);
    frf.H.push_back(r.AtTheta(2 * std::numbers::pi * f * T));
    frf.H_std.push_back(1e-3 * std::abs(frf.H.back()));
    frf.coherence.push_back(1.0);
  }
  const int n = static_cast<int>(truth.modes.size());
  const std::optional<model::Plant> s = LinearRationalStart(frf, n, 0);
  ASSERT_TRUE(s.has_value());
  ASSERT_EQ(static_cast<int>(s->modes.size()), n);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(s->modes[i].omega, truth.modes[i].omega, 0.03 * truth.modes[i].omega) << i;
    EXPECT_NEAR(s->modes[i].v, truth.modes[i].v, 0.03 * truth.modes[i].v) << i;
  }
}

}  // namespace
}  // namespace zwidth::fit::internal
