// Passivity::At (Colgate and Schenkel's passive K at one B) against a
// reference written here: the condition b > K P(theta) - B R(theta) evaluated
// from its definition (the Dirichlet kernel P as its cosine sum, R =
// Re{e^{-j(D+1)theta} F}) on a
// 50 001-point theta grid, with every local extremum of (b + B R)/P refined by
// golden section. The reference skips nothing and shares no code with At (not
// its grid, not its pruning of candidates). Both signs of B are visited, and
// a second test picks loops whose passive set has a lower end K_lo > 0.
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "stability/loop_options.h"
#include "stability/passivity.h"
#include "stability/velocity_filter.h"

namespace zwidth::stability {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// P and R at theta, from their definitions.
void DirectPR(double T, int D, const LoopOptions& l, double th, double* P, double* R) {
  *P = 0.5 * T;  // P = (T/2) sum_{k=-D..D} cos(k theta), the Dirichlet kernel as its sum
  for (int k = 1; k <= D; ++k) *P += T * std::cos(k * th);
  std::complex<double> F = 1.0;
  if (!l.filter_b.empty()) {
    std::complex<double> nb = 0.0, na = 0.0;
    for (size_t i = 0; i < l.filter_b.size(); ++i) nb += l.filter_b[i] * std::polar(1.0, -double(i) * th);
    for (size_t i = 0; i < l.filter_a.size(); ++i) na += l.filter_a[i] * std::polar(1.0, -double(i) * th);
    F = nb / na;
  }
  *R = (std::polar(1.0, -(D + 1) * th) * F).real();
}

// A stable second-order low-pass with unit DC gain and poles rad e^{+-j phi}.
void SetResonantLowPass(double rad, double phi, LoopOptions* l) {
  l->filter_a = {1.0, -2 * rad * std::cos(phi), rad * rad};
  const double dc = l->filter_a[0] + l->filter_a[1] + l->filter_a[2];
  l->filter_b = {0.5 * dc, 0.5 * dc};
}

struct Loop {
  double b, T;
  int D;
  LoopOptions l;
};

// The smallest upper bound (sign +1, over P > 0) or minus the largest lower
// bound (sign -1, over P < 0) of K at B, on an n-point grid, refined or not.
double Extreme(const Loop& c, double B, double sign, int n, bool refine) {
  auto f = [&](double th) {
    double P, R;
    DirectPR(c.T, c.D, c.l, th, &P, &R);
    if (sign > 0) return P > 0 ? (c.b + B * R) / P : kInf;
    return P < 0 ? -(c.b + B * R) / P : kInf;
  };
  auto golden = [&](double a, double e) {
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = e - g * (e - a), x2 = a + g * (e - a), f1 = f(x1), f2 = f(x2);
    for (int it = 0; it < 200 && e - a > 1e-13; ++it) {
      if (f1 < f2) { e = x2; x2 = x1; f2 = f1; x1 = e - g * (e - a); f1 = f(x1); }
      else { a = x1; x1 = x2; f1 = f2; x2 = a + g * (e - a); f2 = f(x2); }
    }
    return std::min(f1, f2);
  };
  std::vector<double> v(n + 1);
  for (int i = 0; i <= n; ++i) v[i] = f(std::numbers::pi * i / n);
  double best = kInf;
  for (int i = 0; i <= n; ++i) {
    best = std::min(best, v[i]);
    if (refine && i > 0 && i < n && std::isfinite(v[i]) && v[i] <= v[i - 1] && v[i] <= v[i + 1])
      best = std::min(best, golden(std::numbers::pi * (i - 1) / n, std::numbers::pi * (i + 1) / n));
  }
  return best;
}

void ExpectMatches(const Loop& c, double B, const std::string& where, int* empty, int* with_lower) {
  const double hi = Extreme(c, B, 1.0, 50000, true), lo = std::max(0.0, -Extreme(c, B, -1.0, 50000, true));
  bool zero_fail = false;  // P = 0 exactly on the grid: the condition reads b + B R > 0
  for (int i = 0; i <= 50000; ++i) {
    double P, R;
    DirectPR(c.T, c.D, c.l, std::numbers::pi * i / 50000, &P, &R);
    zero_fail = zero_fail || (P == 0.0 && !(c.b + B * R > 0));
  }
  const bool ref_empty = zero_fail || !(hi > lo);
  const Passivity passivity(c.b, c.T, c.D, c.l);
  const PassiveInterval got = passivity.At(B);
  // KHi searches the lower bounds only down to K_hi: the same K_hi as At's full search.
  EXPECT_EQ(passivity.KHi(B), got.K_hi) << where;
  ASSERT_EQ(got.passive_set_empty, ref_empty) << where << " K_hi " << hi << " K_lo " << lo;
  if (ref_empty) { ++*empty; return; }
  EXPECT_NEAR(got.K_hi, hi, 1e-9 * hi) << where;
  EXPECT_NEAR(got.K_lo, lo, 1e-9 * hi) << where;
  if (lo > 0) ++*with_lower;
}

TEST(Passivity, MatchesAnUnprunedDenseReferenceForRandomLoopsAndSignedDamping) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0, with_lower = 0, empty = 0;
  for (int k = 0; k < 40; ++k) {
    Loop c{std::pow(10.0, -4.0 + 3.0 * u(rng)), std::pow(10.0, -4.0 + 1.5 * u(rng)), static_cast<int>(13 * u(rng)), {}};
    if (k % 3 == 1) SetLowPassFilter((0.01 + 0.4 * u(rng)) / c.T, c.T, &c.l);
    if (k % 3 == 2) {
      const double rad = 0.3 + 0.65 * u(rng), phi = std::numbers::pi * u(rng);
      SetResonantLowPass(rad, phi, &c.l);
    }
    for (double frac : {-1.5, -0.6, 0.0, 0.3, 0.9}) {
      const double B = frac * c.b * (1.0 + u(rng));
      ExpectMatches(c, B, "case " + std::to_string(k) + " D=" + std::to_string(c.D) + " B=" + std::to_string(B),
                    &empty, &with_lower);
      ++compared;
    }
  }
  EXPECT_EQ(compared, 200);
  EXPECT_GT(empty, 10);  // both outcomes are reached
  EXPECT_GT(compared - empty, 100);
}

// A lower end above zero needs b + B R < 0 inside a lobe where P < 0 and not
// at its edges (where P -> 0 would send K_hi to -inf): a resonant velocity
// filter can do that. Loops are drawn until 12 have, on a coarse unrefined
// 2000-point reading of the definition, a passive set with K_lo > 0 (about 1
// draw in 80), and each is then compared with the refined reference.
TEST(Passivity, MatchesTheReferenceWhereThePassiveSetHasALowerEndAboveZero) {
  std::mt19937_64 rng(1997);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int found = 0, empty = 0, with_lower = 0, draws = 0;
  for (; draws < 20000 && found < 12; ++draws) {
    Loop c{std::pow(10.0, -3.0 + 2.0 * u(rng)), 1e-3, 2 + static_cast<int>(8 * u(rng)), {}};
    const double rad = 0.5 + 0.45 * u(rng), phi = 2.0 + 1.1 * u(rng);
    SetResonantLowPass(rad, phi, &c.l);
    const double B = c.b * (-0.8 + 1.4 * u(rng));
    const double hi = Extreme(c, B, 1.0, 2000, false), lo = -Extreme(c, B, -1.0, 2000, false);
    if (!(lo > 0 && hi > 1.01 * lo)) continue;
    ++found;
    ExpectMatches(c, B, "draw " + std::to_string(draws) + " D=" + std::to_string(c.D) + " B=" + std::to_string(B),
                  &empty, &with_lower);
  }
  EXPECT_EQ(found, 12) << draws << " draws";
  EXPECT_GE(with_lower, 10);
}

}  // namespace
}  // namespace zwidth::stability
