// The Nyquist count of the Z-width (stability/zwidth.h, Crossings and
// IntervalsFrom): where the eigenvalues decide, the number of closed-loop
// roots outside the circle in each K region follows from K -> 0+ and the
// direction of every crossing, without an eigenvalue test per region; the
// count at K = 0+ is computed once per interval between the B where the
// K = 0 boundary is crossed. Checked against a brute force independent of
// the code under test: tests/brute_force.h's own realisation and ZOH of
// eq. (1) (IndependentZoh) closed by LoopBruteForce (its own loop matrix),
// whose eigenvalues are counted here.
//
// Cases: Table I at long delays (170; 200 with the filter; past ~163 samples its characteristic
// polynomial's boundary error exceeds 1e-9, so the eigenvalues decide), the
// issue-31 family of 8 crowded sections at a short delay (eigenvalues from
// the start), each also with a 50 Hz velocity low-pass.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/plant.h"
#include "stability/loop_options.h"
#include "stability/numerics_internal.h"
#include "stability/velocity_filter.h"
#include "stability/zwidth.h"
#include "tests/brute_force.h"

namespace zwidth::stability {
namespace {

model::Plant Crowded() {  // issue 31: 8 sections 8 % apart, damping ratio 0.025
  model::Plant p;
  p.m = 1.168e-3;
  p.b = 0.00584;
  for (int i = 0; i < 8; ++i) {
    const double w = 300.0 * std::pow(1.08, i), v = 0.93 * w;
    p.modes.push_back({w, 0.05 * w, v, 0.05 * v});
  }
  return p;
}

struct Case {
  std::string name;
  model::Plant plant;
  int delay;
  bool filter;
};

std::vector<Case> Cases() {
  return {{"Table I, d = 170", model::PhantomTable1(), 170, false},
          {"Table I, d = 200, 50 Hz filter", model::PhantomTable1(), 200, true},
          {"8 crowded sections, d = 2", Crowded(), 2, false},
          {"8 crowded sections, d = 6, 50 Hz filter", Crowded(), 6, true}};
}

struct Brute {
  LoopBruteForce bf;
  int Outside(double K, double B) const {
    const Eigen::VectorXcd ev = bf.Matrix(K, B).eigenvalues();
    int n = 0;
    for (int i = 0; i < ev.size(); ++i) n += !(std::abs(ev(i)) < 1.0);
    return n;
  }
};

Brute MakeBrute(const Case& c, const LoopOptions& l) {
  const IndependentZoh<double> zoh(c.plant, 1e-3);
  return {LoopBruteForce(zoh.A, zoh.B, zoh.C, l.filter_b, l.filter_a, c.delay + c.plant.delay_samples, 1e-3)};
}

LoopOptions LoopOf(const Case& c) {
  LoopOptions l;
  if (c.filter) SetLowPassFilter(50.0, 1e-3, &l);
  return l;
}

// The B values: 0, and n across (0, 1.2 B_max): 5, or 2 at long delays
// (each B costs the brute force one O(d^3) eigenvalue problem per crossing).
std::vector<double> BValues(const ZWidth& z) {
  const double b_max = z.Summarize().B_max;
  const int n = z.total_delay() > 100 ? 2 : 5;
  std::vector<double> bs = {0.0};
  for (int i = 1; i <= n; ++i) bs.push_back(1.2 * b_max * i / (n + 0.3));
  return bs;
}

TEST(ZWidthCount, EveryKnownDirectionIsTheBruteForcesChangeOfCount) {
  for (const Case& c : Cases()) {
    const LoopOptions l = LoopOf(c);
    const ZWidth z(c.plant, 1e-3, c.delay, l);
    ASSERT_FALSE(z.uses_polynomial_test()) << c.name << ": the case must be one the eigenvalues decide";
    const Brute brute = MakeBrute(c, l);
    int checked = 0, known = 0, total = 0;
    for (double B : BValues(z)) {
      std::vector<Crossing> xs;
      for (const Crossing& x : z.Crossings(B)) if (x.K > 0.0 && std::isfinite(x.K)) xs.push_back(x);
      std::sort(xs.begin(), xs.end(), [](const Crossing& a, const Crossing& b) { return a.K < b.K; });
      for (size_t i = 0; i < xs.size(); ++i) {
        ++total;
        known += xs[i].direction != 0;
        // An isolated crossing (no other within 1e-3), about 10 per B: the
        // count changes by the roots that cross there, with their direction.
        // (1e-4 across: the unbalanced brute force cannot place the real root
        // near -1 to 1e-6 in K at K ~ 1e4 and d = 170.)
        const bool isolated = (i == 0 || xs[i].K - xs[i - 1].K > 1e-3 * xs[i].K) &&
                              (i + 1 == xs.size() || xs[i + 1].K - xs[i].K > 1e-3 * xs[i].K);
        const size_t stride = std::max<size_t>(1, xs.size() / 10);
        if (!isolated || xs[i].direction == 0 || (i % stride != 0 && i + 1 != xs.size())) continue;
        const int weight = xs[i].theta < 3.14159265 ? 2 : 1;
        const int change = brute.Outside(xs[i].K * (1 + 1e-4), B) - brute.Outside(xs[i].K * (1 - 1e-4), B);
        EXPECT_EQ(change, weight * xs[i].direction)
            << c.name << ", B = " << B << ", crossing at K = " << xs[i].K << ", theta = " << xs[i].theta;
        ++checked;
      }
    }
    EXPECT_GT(checked, 10) << c.name;
    EXPECT_GE(known, total * 3 / 4) << c.name << ": most directions are known";
  }
}

TEST(ZWidthCount, IntervalsAreTheBruteForcesStableRegions) {
  for (const Case& c : Cases()) {
    const LoopOptions l = LoopOf(c);
    const ZWidth z(c.plant, 1e-3, c.delay, l);
    const Brute brute = MakeBrute(c, l);
    for (double B : BValues(z)) {
      // The brute force's own classification of every region between
      // consecutive crossings (at its geometric middle), merged into intervals.
      std::vector<double> ks = {0.0};
      for (const Crossing& x : z.Crossings(B)) if (x.K > 0.0 && std::isfinite(x.K)) ks.push_back(x.K);
      std::sort(ks.begin(), ks.end());
      ks.push_back(INFINITY);
      std::vector<std::pair<double, double>> expected;
      for (size_t i = 0; i + 1 < ks.size(); ++i) {
        if (ks[i + 1] - ks[i] <= 1e-12 * ks[i + 1]) continue;
        const double probe = i == 0 ? 0.5 * ks[1] : std::isinf(ks[i + 1]) ? 2.0 * ks[i] : std::sqrt(ks[i] * ks[i + 1]);
        if (brute.Outside(probe, B) != 0) continue;
        if (!expected.empty() && expected.back().second == ks[i]) expected.back().second = ks[i + 1];
        else expected.push_back({ks[i], ks[i + 1]});
      }
      const std::vector<KInterval> got = z.StableIntervals(B);
      ASSERT_EQ(got.size(), expected.size()) << c.name << ", B = " << B;
      for (size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].K_lo, expected[k].first) << c.name << ", B = " << B;
        EXPECT_EQ(got[k].K_hi, expected[k].second) << c.name << ", B = " << B;
        EXPECT_TRUE(got[k].verified) << c.name << ", B = " << B << ", interval " << k;
      }
      const CriticalPoint cp = z.At(B);
      EXPECT_TRUE(cp.verified) << c.name << ", B = " << B;
      EXPECT_EQ(cp.unstable_at_zero_k, expected.empty() || expected[0].first != 0.0) << c.name << ", B = " << B;
    }
  }
}

TEST(ZWidthCount, TheCountAtZeroKIsTheBruteForcesAtEveryB) {
  // K = 0+ per interval between the K = 0 boundary's B values: the count is
  // computed at the first B asked in an interval and reused; here on a grid
  // fine enough to put many B in each interval, against the brute force at
  // K = 1e-7 K_cr(B) (the integrator's root is then inside by ~1e-9).
  for (const Case& c : Cases()) {
    const LoopOptions l = LoopOf(c);
    const ZWidth z(c.plant, 1e-3, c.delay, l);
    const Brute brute = MakeBrute(c, l);
    const double b_hi = 1.5 * z.Summarize().B_max;
    int unstable = 0;
    for (int i = 0; i <= 40; ++i) {
      const double B = b_hi * i / 40.0;
      double k1 = INFINITY;
      for (const Crossing& x : z.Crossings(B)) if (x.K > 0.0) k1 = std::min(k1, x.K);
      const double k = std::isfinite(k1) ? 1e-7 * k1 : 1e-9;
      const int expected = brute.Outside(k, B);
      EXPECT_EQ(z.UnstableRoots(0.0, B), expected) << c.name << ", B = " << B;
      unstable += expected > 0;
    }
    EXPECT_GT(unstable, 0) << c.name << ": the grid reaches past B_max_from_zero";
  }
}

TEST(ZWidthCount, EveryKnownChangeAtZeroKIsTheBruteForcesAndTheCountsFollow) {
  // The counts at K = 0+ of the intervals between the K = 0 boundary's B
  // values are propagated from every 8th by the changes zero_k_changes()
  // gives: each known change must be the brute force's change of count
  // across its B, and every interval's count the brute force's, at its
  // midpoint (at K = 1e-7 K_cr as above).
  for (const Case& c : Cases()) {
    const LoopOptions l = LoopOf(c);
    const ZWidth z(c.plant, 1e-3, c.delay, l);
    const Brute brute = MakeBrute(c, l);
    const std::vector<double>& bs = z.zero_k_boundary();
    const std::vector<int>& changes = z.zero_k_changes();
    ASSERT_EQ(bs.size(), changes.size()) << c.name;
    auto expected = [&](double B) {
      double k1 = INFINITY;
      for (const Crossing& x : z.Crossings(B)) if (x.K > 0.0) k1 = std::min(k1, x.K);
      // No crossing with K > 0 (past the last boundary B): every K > 0 counts
      // as K -> 0+; K = 1 keeps the integrator's root ~1e-4 inside, where the
      // brute force's eigenvalues can place it (at 1e-9 it is within 1e-12).
      return brute.Outside(std::isfinite(k1) ? 1e-7 * k1 : 1.0, B);
    };
    std::vector<double> mids;  // a B inside each interval
    for (size_t i = 0; i <= bs.size(); ++i) {
      const double lo = i == 0 ? 0.0 : bs[i - 1];
      mids.push_back(i == bs.size() ? 2.0 * lo : 0.5 * (lo + bs[i]));
    }
    std::vector<int> counts;
    for (double B : mids) counts.push_back(expected(B));
    int known = 0;
    for (size_t i = 0; i < bs.size(); ++i) {
      if (changes[i] == 0) continue;
      ++known;
      EXPECT_EQ(counts[i + 1] - counts[i], changes[i]) << c.name << ", K = 0 boundary at B = " << bs[i];
    }
    EXPECT_GE(known, static_cast<int>(bs.size()) * 3 / 4) << c.name << ": most changes are known";
    for (size_t i = 0; i < mids.size(); ++i) {
      EXPECT_EQ(z.UnstableRoots(0.0, mids[i]), counts[i]) << c.name << ", interval " << i << ", B = " << mids[i];
    }
  }
}

TEST(ZWidthCount, APropagatedCountOutsideZeroToTheOrderFallsBackToCounting) {
  // FillZeroKBlock's rule (internal::PropagateCounts) with directions
  // injected by hand, in a closed loop of order 4 counted 3 roots outside at
  // both ends of a block of two boundary crossings. Right directions: a pair
  // in, then out again.
  std::vector<int> counts;
  ASSERT_TRUE(internal::PropagateCounts(3, 3, {-2, +2}, 4, &counts));
  EXPECT_EQ(counts, std::vector<int>{1});
  // Both directions wrong: the sum still reaches the end's count, but the
  // middle count would be 5 roots outside a loop of order 4 (the rule before
  // the cap kept it): rejected, the slot is then counted by the eigenvalues.
  EXPECT_FALSE(internal::PropagateCounts(3, 3, {+2, -2}, 4, &counts));
  EXPECT_TRUE(counts.empty());
  // Below 0, an unknown direction (0) and a sum that misses the end.
  EXPECT_FALSE(internal::PropagateCounts(1, 1, {-2, +2}, 4, &counts));
  EXPECT_FALSE(internal::PropagateCounts(1, 1, {+2, 0, -2}, 4, &counts));
  EXPECT_FALSE(internal::PropagateCounts(1, 3, {+2, -2}, 4, &counts));
  // The step IntervalsFrom uses along K: a known change of 0 (a tangency) is
  // kept, the range [0, order] is inclusive.
  EXPECT_EQ(internal::PropagateCount(2, 0, true, 4), 2);
  EXPECT_EQ(internal::PropagateCount(3, 1, true, 4), 4);
  EXPECT_EQ(internal::PropagateCount(4, 1, true, 4), -1);
  EXPECT_EQ(internal::PropagateCount(1, -2, true, 4), -1);
  EXPECT_EQ(internal::PropagateCount(1, 2, false, 4), -1);
  EXPECT_EQ(internal::PropagateCount(-1, 2, true, 4), -1);
}

}  // namespace
}  // namespace zwidth::stability
