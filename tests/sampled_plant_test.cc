// stability/sampled_plant.h: one sampled plant shared by every delay, the
// comparison, the rows and the figures, checked against an independent
// closed-loop brute force.
#include <cmath>
#include <cstdio>
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

// G_d(z) of eq. (1) from the tests' own realisation, sampled by Eigen's
// matrix exponential in long double (tests/brute_force.h, IndependentZoh: 3
// digits more than double) and solved by a dense LU in long double: a
// reference independent of model/zoh_modal.h and model/state_space.cc.
std::complex<long double> LongDoubleZoh(const model::Plant& p, double T, std::complex<double> z) {
  using R = long double;
  using CMat = Eigen::Matrix<std::complex<R>, Eigen::Dynamic, Eigen::Dynamic>;
  const IndependentZoh<R> zoh(p, T);
  const int n = static_cast<int>(zoh.A.rows());
  const CMat zI = CMat::Identity(n, n) * std::complex<R>(z.real(), z.imag());
  const CMat x = (zI - zoh.A.cast<std::complex<R>>()).partialPivLu().solve(zoh.B.cast<std::complex<R>>());
  return (zoh.C.cast<std::complex<R>>() * x)(0, 0);
}

double RelativeError(std::complex<double> g, std::complex<long double> ref) {
  return static_cast<double>(std::abs(std::complex<long double>(g.real(), g.imag()) - ref) / std::abs(ref));
}

// Issue 31, 64 sections 8 % apart at damping ratio 0.025 (the many-mode
// benchmark's model, up to 6 kHz at T = 1 ms): the double matrix exponential
// of the 130-state ZOH is off by ~1e-8 near 70 Hz, so the pole-residue form
// (O(n) per point) is the exact one there, and SampledPlant uses it. Before,
// Gd fell back to the state space (held to agree with it) and this failed at
// 1.5e-8.
TEST(SampledPlant, ManyWideBandModesUseThePoleResidueFormWhereItIsTheExactOne) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < 64; ++i) {
    const double w = 300.0 * std::pow(1.08, i), v = 0.93 * w;
    p.modes.push_back({w, 0.05 * w, v, 0.05 * v});
  }
  const SampledPlant sp(p, 1e-3);
  double worst_gd = 0.0, worst_state_space = 0.0;
  for (int k = 1; k < 24; ++k) {
    const std::complex<double> z = std::polar(1.0, 0.25 + 0.3 * k / 24.0);  // 40-87 Hz, where the ZOH errs most
    const std::complex<long double> ref = LongDoubleZoh(p, 1e-3, z);
    worst_gd = std::max(worst_gd, RelativeError(sp.Gd(z), ref));
    worst_state_space = std::max(worst_state_space, RelativeError(sp.GdStateSpace(z), ref));
  }
  std::printf("64 sections: Gd %.3g, state space %.3g from the long double ZOH\n", worst_gd, worst_state_space);
  EXPECT_LE(worst_gd, 1e-10);
  // The reference resolves the state space's error (else the test proves nothing).
  EXPECT_GT(worst_state_space, 1e-9);
}

// Where the modes crowd (8 sections 1 % apart at damping 1e-4) the double
// pole-residue sum cancels (its terms 1e10 times G_d) and the double state
// space errs near the modes (its poles rounded); SampledPlant then sums the
// pole-residue form in binary128. Against the long double ZOH (its own error
// ~2000 times below the double one's) at every 80th mode-patch point. Before,
// Gd was the state space and this failed at 1.2e-6.
TEST(SampledPlant, CrowdedModesUseThePoleResidueFormInBinary128) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < 8; ++i) {
    const double w = 300.0 * std::pow(1.01, i), v = 0.93 * w;
    p.modes.push_back({w, 2e-4 * w, v, 2e-4 * v});
  }
  const SampledPlant sp(p, 1e-3);
  EXPECT_FALSE(sp.gd_pole_residue());
#if defined(__SIZEOF_FLOAT128__)
  EXPECT_TRUE(sp.gd_binary128());
  double worst_gd = 0.0, worst_state_space = 0.0;
  for (size_t i = 0; i < sp.mode_patch_theta().size(); i += 80) {
    const std::complex<double> z = std::polar(1.0, sp.mode_patch_theta()[i]);
    const std::complex<long double> ref = LongDoubleZoh(p, 1e-3, z);
    worst_gd = std::max(worst_gd, RelativeError(sp.Gd(z), ref));
    worst_state_space = std::max(worst_state_space, RelativeError(sp.GdStateSpace(z), ref));
  }
  std::printf("8 crowded sections: Gd %.3g, state space %.3g from the long double ZOH\n", worst_gd, worst_state_space);
  EXPECT_LE(worst_gd, 1e-8);
  EXPECT_GT(worst_state_space, 1e-7);  // the reference resolves the state space's error
#else
  EXPECT_FALSE(sp.gd_binary128());
#endif
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
