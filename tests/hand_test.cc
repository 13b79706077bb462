// stability/hand.h: the plant with the user's hand (moved from haptic_loop_test.cc,
// tests unchanged), against independent references:
// - the hand's state space against G / (1 + G Z_h) from the plant's formula;
// - the intersection of the stable intervals of several hands against
//   IsStable of every hand, K by K.
// Random devices: seeded (test::RandomPlausibleDevice).
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "model/plant.h"
#include "model/state_space.h"
#include "stability/hand.h"
#include "stability/loop_options.h"
#include "stability/velocity_filter.h"
#include "stability/zwidth.h"
#include "tests/hands.h"
#include "tests/test_util.h"

namespace zwidth::stability {
namespace {

TEST(HapticLoop, HandStateSpaceIsGOverOnePlusGZ) {
  std::mt19937_64 rng(16);
  for (int k = 0; k < 8; ++k) {
    const model::Plant p = test::RandomPlausibleDevice(rng, k % 4);
    const Hand h = HandOf(1 + k % 2, p);
    const model::StateSpace s = ContinuousStateSpaceWithHand(p, h);
    const int n = static_cast<int>(s.A.rows());
    for (double w : {0.3, 7.0, 60.0, 500.0, 2500.0}) {
      const std::complex<double> jw(0.0, w);
      const std::complex<double> g = model::ContinuousResponse(p, w);
      const std::complex<double> want = g / (1.0 + g * (h.M * jw * jw + h.B * jw + h.K));
      const Eigen::MatrixXcd R = jw * Eigen::MatrixXcd::Identity(n, n) - s.A.cast<std::complex<double>>();
      const std::complex<double> got =
          (s.C.cast<std::complex<double>>() * R.partialPivLu().solve(s.B.cast<std::complex<double>>()))(0);
      EXPECT_LT(std::abs(got - want), 1e-9 * std::abs(want)) << "k=" << k << " w=" << w;
    }
  }
}

TEST(HapticLoop, IntersectionOfHandsIsStableForEveryHand) {
  std::mt19937_64 rng(8);
  const model::Plant p = test::RandomPlausibleDevice(rng, 2);
  std::vector<ZWidth> zs;
  for (int h = 0; h < 3; ++h) {
    LoopOptions l;
    l.hand = HandOf(h, p);
    SetLowPassFilter(50.0, 1e-3, &l);
    zs.emplace_back(p, 1e-3, 4, l);
  }
  const double Bm = zs[0].Summarize().B_max;
  for (int i = 0; i < 40; ++i) {
    const double B = 1.2 * Bm * i / 39;
    std::vector<KInterval> all = zs[0].StableIntervals(B);
    for (int h = 1; h < 3; ++h) all = IntersectIntervals(all, zs[h].StableIntervals(B));
    for (int j = 0; j < 200; ++j) {
      const double K = 1e-2 * std::pow(1e6, j / 199.0) * p.m / 1e-6 * 1e-3;
      bool in = false;
      for (const KInterval& v : all) in = in || (K > v.K_lo && K < v.K_hi);
      bool every = true;
      for (const ZWidth& z : zs) every = every && z.IsStable(K, B);
      const bool edge = zs[0].IsStable(K * (1 + 1e-9), B) != zs[0].IsStable(K * (1 - 1e-9), B) ||
                        zs[1].IsStable(K * (1 + 1e-9), B) != zs[1].IsStable(K * (1 - 1e-9), B) ||
                        zs[2].IsStable(K * (1 + 1e-9), B) != zs[2].IsStable(K * (1 - 1e-9), B);
      if (!edge) EXPECT_EQ(in, every) << "B=" << B << " K=" << K;
    }
  }
}

}  // namespace
}  // namespace zwidth::stability
