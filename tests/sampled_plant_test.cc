// stability/sampled_plant.h: one sampled plant shared by every delay, the
// comparison, the rows and the figures gives the numbers of the one-loop
// constructors of ZWidth.
#include <cmath>
#include <complex>
#include <stdexcept>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/state_space.h"
#include "stability/sampled_plant.h"
#include "stability/zwidth.h"

namespace zwidth::stability {
namespace {

// A ZWidth on a shared SampledPlant is the same computation as the one-loop
// constructor: every number bit-identical, at several delays, with and without
// a velocity filter and a hand; and G_d of the sampled plant is the ZOH
// response of model/state_space.h.
TEST(SampledPlant, SharedByDelaysGivesTheOneLoopConstructorsNumbers) {
  const model::Plant p = model::PhantomTable1();
  LoopOptions filt;
  filt.filter_b = {0.2};
  filt.filter_a = {1.0, -0.8};
  LoopOptions hand = filt;
  hand.hand = {0.3 * p.m, p.b, 50.0};
  for (const LoopOptions& l : {LoopOptions{}, filt, hand}) {
    const SampledPlant sp(p, 1e-3, l.hand);
    for (int d : {0, 2, 7}) {
      const ZWidth a(sp, d, l), b(p, 1e-3, d, l);
      const DelaySummary sa = a.Summarize(), sb = b.Summarize();
      EXPECT_EQ(sa.K_cr_at_zero_B, sb.K_cr_at_zero_B);
      EXPECT_EQ(sa.K_cr_max, sb.K_cr_max);
      EXPECT_EQ(sa.B_max, sb.B_max);
      for (double B : {0.0, 0.01, 0.05}) {
        const auto ia = a.StableIntervals(B), ib = b.StableIntervals(B);
        ASSERT_EQ(ia.size(), ib.size());
        for (size_t k = 0; k < ia.size(); ++k) {
          EXPECT_EQ(ia[k].K_lo, ib[k].K_lo);
          EXPECT_EQ(ia[k].K_hi, ib[k].K_hi);
        }
      }
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
