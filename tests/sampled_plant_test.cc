// stability/sampled_plant.h: one sampled plant shared by every delay, the
// comparison, the rows and the figures, checked against an independent
// closed-loop brute force.
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/state_space.h"
#include "stability/sampled_plant.h"
#include "stability/zwidth.h"
#include "tests/brute_force.h"

namespace zwidth::stability {
namespace {

// A ZWidth on a shared SampledPlant, at several delays, with and without a
// velocity filter and a hand, against the independent closed-loop brute force
// (tests/brute_force.h: its own ZOH and the loop's eigenvalues): K_CR(0) and
// the upper end of the interval from 0 at two dampings to 1e-7, and the
// stable intervals on a (K, B) grid; and G_d of the sampled plant is the ZOH
// response of model/state_space.h.
TEST(SampledPlant, SharedByDelaysAgreesWithTheClosedLoopsEigenvalues) {
  const model::Plant p = model::PhantomTable1();
  LoopOptions filt;
  filt.filter_b = {0.2};
  filt.filter_a = {1.0, -0.8};
  LoopOptions hand = filt;
  hand.hand = {0.3 * p.m, p.b, 50.0};
  const LoopOptions loops[] = {LoopOptions{}, filt, hand};
  for (const LoopOptions& l : loops) {
    const SampledPlant sp(p, 1e-3, l.hand);
    for (int d : {0, 2, 7}) {
      const ZWidth a(sp, d, l);
      const LoopBruteForce brute = MakeBrute(p, l, d, 1e-3);
      auto max_root = [&](double K, double B) { return brute.MaxRoot(K, B); };
      const std::string at = "d = " + std::to_string(d) + (&l == &loops[0] ? "" : &l == &loops[1] ? ", filter" : ", filter and hand");
      const double k0 = KCriticalOf(max_root, 0.0);
      EXPECT_NEAR(a.Summarize().K_cr_at_zero_B, k0, 1e-7 * k0) << at;
      for (double B : {0.01, 0.05}) {
        const std::vector<KInterval> iv = a.StableIntervals(B);
        const double kb = KCriticalOf(max_root, B);
        if (kb == 0.0) {
          EXPECT_TRUE(iv.empty() || iv[0].K_lo > 0.0) << at << " B = " << B;
        } else {
          ASSERT_FALSE(iv.empty()) << at << " B = " << B;
          EXPECT_EQ(iv[0].K_lo, 0.0) << at << " B = " << B;
          EXPECT_NEAR(iv[0].K_hi, kb, 1e-7 * kb) << at << " B = " << B;
        }
      }
      const Tally t = Classify(a, max_root, p, 1e-3, d, ClassifyGrid{.b_top = 0.06, .num_b = 4, .min_points = 120, .points_inside = 3});
      EXPECT_EQ(t.disagree, 0) << at;
      EXPECT_GT(t.stable, 0) << at;
    }
  }
  // The response against a dense LU solve of C (zI - A)^-1 B + D on the ZOH
  // state space (not the Hessenberg solve SampledPlant uses), and Gd (the
  // pole-residue sum) against the same.
  const SampledPlant sp(p, 1e-3);
  const model::StateSpace ss = model::DiscretizeZoh(p, 1e-3);
  for (double th : {0.01, 0.5, 2.0}) {
    const std::complex<double> z = std::polar(1.0, th);
    const Eigen::MatrixXcd M = z * Eigen::MatrixXcd::Identity(ss.A.rows(), ss.A.cols()) - ss.A.cast<std::complex<double>>();
    const std::complex<double> dense =
        (ss.C.cast<std::complex<double>>() * M.partialPivLu().solve(ss.B.cast<std::complex<double>>()))(0) + ss.D;
    const std::complex<double> b = dense * std::polar(1.0, -th * ss.delay_samples);
    EXPECT_LE(std::abs(sp.AtTheta(th) - b), 1e-10 * std::abs(b)) << th;
    EXPECT_LE(std::abs(sp.Gd(z) - dense), 1e-10 * std::abs(dense)) << th;
  }
}

// The mode patches hold every point the code intends: 641 points spaced c T / 16
// around the damped frequency of each resonance and antiresonance (before the
// fix only one point per patch survived).
TEST(SampledPlant, ModePatchesAreDenseAroundEveryMode) {
  model::Plant p;
  p.m = 1e-3;
  p.b = 5e-3;
  p.modes = {{2 * std::numbers::pi * 200, 2.0, 2 * std::numbers::pi * 150, 1.5},
             {2 * std::numbers::pi * 400, 0.3, 2 * std::numbers::pi * 330, 0.2}};
  const double T = 1e-3;
  const SampledPlant sp(p, T);  // the grid is the plant's: a reference into a temporary would dangle
  const std::vector<double>& th = sp.mode_patch_theta();
  ASSERT_EQ(th.size(), 4u * (2 * kModePatchHalfWidth + 1));
  for (const model::Mode& md : p.modes) {
    for (auto [w, c] : {std::pair{md.omega, md.c}, std::pair{md.v, md.d}}) {
      const double center = std::sqrt(w * w - c * c / 4) * T, h = c * T / 16;
      int near = 0;
      for (double t : th) near += std::abs(t - center) <= (kModePatchHalfWidth + 0.5) * h;
      EXPECT_EQ(near, 2 * kModePatchHalfWidth + 1) << w;
      // The point nearest the center is the center itself (k = 0).
      double best = 1.0;
      for (double t : th) best = std::min(best, std::abs(t - center));
      EXPECT_LT(best, 1e-12) << w;
    }
  }
}

TEST(SampledPlant, AHandOtherThanTheSampledOnesIsABrokenContract) {
  const SampledPlant sp(model::PhantomTable1(), 1e-3);
  LoopOptions l;
  l.hand = {1e-4, 0.0, 0.0};
  EXPECT_THROW(ZWidth(sp, 2, l), std::invalid_argument);
  EXPECT_THROW(ZWidth(sp, -1), InputError);
  EXPECT_THROW(SampledPlant(model::PhantomTable1(), 0.0), InputError);
}

}  // namespace
}  // namespace zwidth::stability
