#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/state_space.h"
#include "stability/relay.h"
#include "stability/schur_cohn.h"
#include "stability/zwidth.h"

namespace zwidth::stability {
namespace {

// Independent brute force: the closed-loop polynomial from the plant's discrete
// state space, N(z) = det(zI - A + BC) - det(zI - A), and its roots as the
// eigenvalues of the companion matrix.
struct BruteForce {
  Eigen::VectorXd den, num;  // z^0 first
  int d;
  double T;
  static Eigen::VectorXd CharPoly(const Eigen::MatrixXd& M) {
    const Eigen::VectorXcd ev = M.eigenvalues();
    Eigen::VectorXcd c = Eigen::VectorXcd::Zero(ev.size() + 1);
    c(0) = 1.0;
    for (int i = 0; i < ev.size(); ++i) {
      for (int k = i + 1; k > 0; --k) c(k) = c(k - 1) - ev(i) * c(k);
      c(0) = -ev(i) * c(0);
    }
    return c.real();
  }
  BruteForce(const Plant& p, double T_, int d_) : d(d_ + p.delay_samples), T(T_) {
    const StateSpace s = DiscretizeZoh(p, T);
    den = CharPoly(s.A);
    num = CharPoly(s.A - s.B * s.C) - den;
  }
  double MaxRoot(double K, double B) const {
    const int n = static_cast<int>(den.size()) - 1;
    Eigen::VectorXd p = Eigen::VectorXd::Zero(n + d + 2);
    p.segment(d + 1, n + 1) += den;
    for (int i = 0; i < num.size(); ++i) {
      p(i + 1) += (K + B / T) * num(i);
      p(i) += -B / T * num(i);
    }
    int deg = static_cast<int>(p.size()) - 1;
    while (deg > 0 && p(deg) == 0) --deg;
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(deg, deg);
    for (int i = 1; i < deg; ++i) C(i, i - 1) = 1.0;
    for (int i = 0; i < deg; ++i) C(i, deg - 1) = -p(i) / p(deg);
    return C.eigenvalues().cwiseAbs().maxCoeff();
  }
  // Smallest K > 0 with a root on the circle, by a geometric scan and bisection.
  double KCritical(double B, double k_lo = 1e-4, double k_hi = 1e5) const {
    if (MaxRoot(k_lo, B) >= 1.0) return 0.0;
    double prev = k_lo;
    for (double k = k_lo * 1.01; k < k_hi; k *= 1.01) {
      if (MaxRoot(k, B) >= 1.0) {
        double a = prev, b = k;
        for (int i = 0; i < 60; ++i) {
          const double m = 0.5 * (a + b);
          (MaxRoot(m, B) >= 1.0 ? b : a) = m;
        }
        return 0.5 * (a + b);
      }
      prev = k;
    }
    return std::numeric_limits<double>::infinity();
  }
};

TEST(ZWidth, AppendixModelFactsAtTwoAndFourSamples) {
  const Plant p = PhantomTable1();
  const DelaySummary s2 = ZWidth(p, 1e-3, 2).Summarize();
  EXPECT_NEAR(s2.B_t, 0.0855, 0.0005);
  EXPECT_NEAR(s2.K_cr_max, 36.74, 0.01);
  EXPECT_NEAR(s2.f_before_hz, 27.8, 0.1);
  EXPECT_NEAR(s2.f_after_hz, 171, 1);
  EXPECT_NEAR(s2.B_max, 0.0997, 0.0001);
  const DelaySummary s4 = ZWidth(p, 1e-3, 4).Summarize();
  EXPECT_NEAR(s4.B_t, 0.2262, 0.0005);
  EXPECT_NEAR(s4.K_cr_max, 35.24, 0.01);
  EXPECT_NEAR(s4.f_before_hz, 33.1, 0.1);
  EXPECT_NEAR(s4.f_after_hz, 259.5, 0.5);
}

TEST(ZWidth, RigidBodyAtTwoSamples) {
  Plant p = PhantomTable1();
  p.modes.clear();
  const CriticalPoint c = ZWidth(p, 1e-3, 2).At(0.0);
  const BruteForce bf(p, 1e-3, 2);
  EXPECT_NEAR(c.K_cr, bf.KCritical(0.0), 1e-6 * c.K_cr);
  // The issue quotes 2.3415 at 7.10 Hz; the root-verified value is 2.34105.
  EXPECT_NEAR(c.K_cr, 2.3415, 0.001);
  EXPECT_NEAR(c.f_cr_hz, 7.10, 0.01);
}

TEST(ZWidth, AgreesWithBruteForceOverDelaysAndDampings) {
  const Plant p = PhantomTable1();
  for (int d = 1; d <= 10; ++d) {
    const ZWidth z(p, 1e-3, d);
    const BruteForce bf(p, 1e-3, d);
    for (int i = 0; i <= 800; ++i) {
      const double B = 0.0005 * i;
      const CriticalPoint c = z.At(B);
      EXPECT_TRUE(c.verified) << d << " " << B;
      if (c.K_cr > 0 && std::isfinite(c.K_cr)) {
        // Root check at +-1e-6 relative, for every point.
        EXPECT_LT(bf.MaxRoot(c.K_cr * (1 - 1e-6), B), 1.0) << d << " " << B;
        EXPECT_GE(bf.MaxRoot(c.K_cr * (1 + 1e-6), B), 1.0) << d << " " << B;
      } else if (c.K_cr == 0) {
        EXPECT_GE(bf.MaxRoot(1e-4, B), 1.0) << d << " " << B;
      }
      if (i % 80 == 0) {  // full scan: also the *first* crossing
        const double ref = bf.KCritical(B);
        if (ref == 0) EXPECT_EQ(c.K_cr, 0.0) << d << " " << B;
        else EXPECT_NEAR(c.K_cr, ref, 1e-6 * ref) << d << " " << B;
      }
    }
  }
}

TEST(ZWidth, MarginReadingStaysPositivePastBMax) {
  const ZWidth z(PhantomTable1(), 1e-3, 2);
  const CriticalPoint c = z.At(0.15);
  EXPECT_EQ(c.K_cr, 0.0);
  EXPECT_TRUE(c.unstable_at_zero_k);
  EXPECT_GT(c.K_margin, 0.0);
  EXPECT_FALSE(c.AgreesWithMargin());
  const CriticalPoint ok = z.At(0.05);
  EXPECT_TRUE(ok.AgreesWithMargin());
}

TEST(ZWidth, StressRandomModelsAgreeWithBruteForce) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Plant p;
    p.m = std::pow(10.0, -5 + 5 * U(rng));
    p.b = p.m * std::pow(10.0, -1 + 2 * U(rng));
    const int nm = trial % 5;
    const double T = 1e-3;
    for (int i = 0; i < nm; ++i) {
      const double w = 2 * std::numbers::pi * (5 + 445 * U(rng));  // up to 0.45 fs
      const double v = w * (0.5 + U(rng));
      const double zc = std::pow(10.0, -3 + 2.7 * U(rng)), zd = std::pow(10.0, -3 + 2.7 * U(rng));
      p.modes.push_back({w, std::max(0.1, 2 * zc * w), std::min(v, 0.95 * std::numbers::pi / T), std::max(0.1, 2 * zd * v)});
    }
    const int d = static_cast<int>(U(rng) * 12);
    const ZWidth z(p, T, d);
    const BruteForce bf(p, T, d);
    const double kscale = p.m / (T * T);
    for (double bfrac : {0.0, 0.3, 1.0}) {
      const double B = bfrac * p.m / T * 0.1;
      const CriticalPoint c = z.At(B);
      if (!(c.K_cr > 0) || !std::isfinite(c.K_cr)) continue;
      // Near a 0.1 rad/s mode a root moves ~1e-10 per 1e-5 of K: test at 1e-3.
      EXPECT_LT(bf.MaxRoot(c.K_cr * (1 - 1e-3), B), 1.0 + 1e-9) << trial;
      EXPECT_GE(bf.MaxRoot(c.K_cr * (1 + 1e-3), B), 1.0 - 1e-9) << trial;
      const double ref = bf.KCritical(B, 1e-6 * kscale, 1e3 * kscale);
      EXPECT_NEAR(c.K_cr, ref, 1e-5 * ref) << "trial " << trial << " d " << d << " B " << B;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(ZWidth, LongDelaysAgreeWithBruteForce) {
  const Plant p = PhantomTable1();
  for (int d : {25, 60, 100}) {
    const ZWidth z(p, 1e-3, d);
    const BruteForce bf(p, 1e-3, d);
    const CriticalPoint c = z.At(0.0);
    EXPECT_NEAR(c.K_cr, bf.KCritical(0.0, 1e-5, 100), 1e-6 * c.K_cr) << d;
  }
}

TEST(SchurCohn, KnownPolynomials) {
  EXPECT_TRUE(AllRootsInsideUnitCircle({0.25, -1.0, 1.0}));   // (z-0.5)^2
  EXPECT_FALSE(AllRootsInsideUnitCircle({-1.0, 0.0, 1.0}));   // roots on the circle
  EXPECT_FALSE(AllRootsInsideUnitCircle({-1.1, 1.0}));        // z = 1.1
  EXPECT_TRUE(AllRootsInsideUnitCircle({0.5}));
}

TEST(ZWidth, DegenerateCases) {
  EXPECT_THROW(ZWidth(PhantomTable1(), 0.0, 2), InputError);
  EXPECT_THROW(ZWidth(PhantomTable1(), 1e-3, -1), InputError);
  // The pole at z = 1: K < 0 is never stable; K = 0+ at B = 0 is.
  const ZWidth z(PhantomTable1(), 1e-3, 2);
  EXPECT_FALSE(z.IsStable(-1e-6, 0.0));
  EXPECT_TRUE(z.IsStable(0.0, 0.0));
}

TEST(Relay, EstimateIsNearTheExactBoundaryBelowTheTransition) {
  const Plant p = PhantomTable1();
  // Measured deviations are reported in docs/performance.md; the describing
  // function itself is off by several % at small B (harmonics of a 1/s^2 plant).
  for (auto [d, B] : std::vector<std::pair<int, double>>{{2, 0.03}, {4, 0.08}, {8, 0.05}, {8, 0.08}}) {
    RelayOptions o;
    o.delay_samples = d;
    o.damping = B;
    const RelayResult r = SimulateRelay(p, o);
    const CriticalPoint c = ZWidth(p, 1e-3, d).At(B);
    ASSERT_TRUE(r.oscillating);
    EXPECT_NEAR(r.K_cr / c.K_cr, 1.0, 0.08) << d << " " << B;
    EXPECT_NEAR(r.f_cr_hz / c.f_cr_hz, 1.0, 0.04) << d << " " << B;
  }
}

}  // namespace
}  // namespace zwidth::stability
