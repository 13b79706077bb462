// stability/uncertainty.h: the standard deviation of K_cr by the delta method
// against a seeded Monte Carlo over the model's parameters.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"
#include "stability/loop_options.h"
#include "stability/velocity_filter.h"
#include "tests/hands.h"
#include "tests/test_util.h"

namespace zwidth::stability {
namespace {

// A covariance with 1-2% relative std and some correlation, seeded.
std::vector<double> TestCovariance(const model::Plant& p, double rel_std, unsigned seed) {
  const int n = NumLogParameters(p);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i) for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  Eigen::MatrixXd S = 0.3 * A * A.transpose() / n + Eigen::MatrixXd::Identity(n, n);
  S *= rel_std * rel_std;
  return std::vector<double>(S.data(), S.data() + n * n);
}

class UncertaintyDelays : public ::testing::TestWithParam<int> {};

TEST_P(UncertaintyDelays, DeltaMethodAgreesWithMonteCarlo) {
  // Table I at d = 2 (a transition and an interior-free K_CR^max at B_t) and
  // d = 8, 1% relative std; 300 seeded samples (std of a sample std ~ 4%).
  const model::Plant p = model::PhantomTable1();
  const std::vector<double> cov = TestCovariance(p, 0.01, 3);
  const int d = GetParam();
  const ZWidth z(p, 1e-3, d);
  const DelaySummary s = z.Summarize();
  const SummaryStd dm = SummaryStdDelta(p, cov, 1e-3, d, s);
  const MonteCarloResult mc = SummaryMonteCarlo(p, cov, 1e-3, d, 300, 11);
  const double pairs[4][2] = {{dm.K_cr_at_zero_B, mc.std.K_cr_at_zero_B}, {dm.B_t, mc.std.B_t},
                              {dm.K_cr_max, mc.std.K_cr_max}, {dm.B_max, mc.std.B_max}};
  for (int q = 0; q < 4; ++q) {
    if (q == 1 && !s.has_transition) continue;
    ASSERT_TRUE(std::isfinite(pairs[q][0]) && pairs[q][0] > 0) << d << " " << q;
    EXPECT_LT(pairs[q][0] / pairs[q][1], 1.5) << "d=" << d << " quantity " << q;
    EXPECT_GT(pairs[q][0] / pairs[q][1], 1 / 1.5) << "d=" << d << " quantity " << q;
    std::printf("d=%d q=%d delta %.4g monte carlo %.4g ratio %.3f\n", d, q, pairs[q][0], pairs[q][1],
                pairs[q][0] / pairs[q][1]);
  }
  // K_CR(B) at a few B below the transition: implicit differentiation
  // against Monte Carlo of At(B).
  std::vector<CriticalPoint> pts;
  for (double f : {0.0, 0.3, 0.6}) pts.push_back(z.At(f * (s.has_transition ? s.B_t : s.B_max_from_zero)));
  const std::vector<double> sd = KcrStd(p, cov, 1e-3, d, pts);
  const int n = NumLogParameters(p);
  const Eigen::MatrixXd S = Eigen::Map<const Eigen::MatrixXd>(cov.data(), n, n);
  const Eigen::MatrixXd L = S.llt().matrixL();
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  std::vector<double> s1(pts.size()), s2(pts.size());
  const int N = 400;
  for (int k = 0; k < N; ++k) {
    Eigen::VectorXd u(n);
    for (int i = 0; i < n; ++i) u[i] = g(rng);
    const Eigen::VectorXd dx = L * u;
    const ZWidth zs(PerturbLog(p, std::vector<double>(dx.data(), dx.data() + n)), 1e-3, d);
    for (size_t j = 0; j < pts.size(); ++j) {
      const double v = zs.At(pts[j].B).K_cr - pts[j].K_cr;
      s1[j] += v;
      s2[j] += v * v;
    }
  }
  for (size_t j = 0; j < pts.size(); ++j) {
    const double m = s1[j] / N, mc_sd = std::sqrt((s2[j] - N * m * m) / (N - 1));
    EXPECT_LT(sd[j] / mc_sd, 1.5) << d << " B=" << pts[j].B;
    EXPECT_GT(sd[j] / mc_sd, 1 / 1.5) << d << " B=" << pts[j].B;
  }
}

INSTANTIATE_TEST_SUITE_P(TableOne, UncertaintyDelays, ::testing::Values(2, 8), test::DelayName());

// The summary std by implicit differentiation on the nominal crossings
// against central differences of the quantities themselves (2 p perturbed
// Z-widths, ZWidth::SummarizeNear): the same derivative two ways, so they
// agree to the differences' truncation error (step 1e-4 in the logs: ~1e-8).
// Table I at d = 1, 2, 4, 8 (K_CR^max at the corner B_t, B_max at the K = 0
// point), and the lightly damped device whose K_CR^max sits where the
// interval from 0+ closes (and whose B_max ends a reopened band past it, where
// the band's last interval closes as its two ends tie).
struct ImplicitCase { const char* name; model::Plant plant; int delay; bool b_max_at_zero_k = true; };
void PrintTo(const ImplicitCase& c, std::ostream* os) { *os << c.name; }
class UncertaintyImplicit : public ::testing::TestWithParam<ImplicitCase> {};

TEST_P(UncertaintyImplicit, ImplicitDerivativesEqualFiniteDifferences) {
  const ImplicitCase& c = GetParam();
  const std::vector<double> cov = TestCovariance(c.plant, 0.01, 3);
  const PerturbedPlants pl = SamplePerturbedPlants(c.plant, 1e-3);
  const ZWidth z(pl.nominal, c.delay);
  const DelaySummary s = z.Summarize();
  const SummaryStd im = SummaryStdImplicit(z, pl, cov, c.delay, s);
  const SummaryStd fd = SummaryStdFiniteDifference(pl, cov, c.delay, s);
  const SummaryStd dm = SummaryStdDelta(z, pl, cov, c.delay, s);
  const double q[4][3] = {{im.K_cr_at_zero_B, fd.K_cr_at_zero_B, dm.K_cr_at_zero_B}, {im.B_t, fd.B_t, dm.B_t},
                          {im.K_cr_max, fd.K_cr_max, dm.K_cr_max}, {im.B_max, fd.B_max, dm.B_max}};
  for (int k = 0; k < 4; ++k) {
    if (k == 1 && !s.has_transition) continue;
    ASSERT_TRUE(std::isfinite(q[k][1]) && q[k][1] > 0) << c.name << " quantity " << k;
    if (k == 3) {  // B_max at the K = 0 point, or at a reopened band's end
      if (c.b_max_at_zero_k) EXPECT_NEAR(s.B_max / s.B_max_from_zero, 1.0, 1e-9) << c.name;
      else EXPECT_GT(s.B_max, (1 + 1e-6) * s.B_max_from_zero) << c.name;
    }
    ASSERT_TRUE(std::isfinite(q[k][0])) << c.name << " quantity " << k << ": not covered by the implicit derivatives";
    EXPECT_NEAR(q[k][0] / q[k][1], 1.0, 1e-6) << c.name << " quantity " << k;
    EXPECT_EQ(q[k][2], q[k][0]) << c.name << " quantity " << k;  // SummaryStdDelta takes the implicit row
  }
}

model::Plant LightlyDamped() {
  const double w = 2 * std::numbers::pi * 120, v = 2 * std::numbers::pi * 100;
  return model::Plant{1e-3, 5e-3, {{w, 2 * 0.001 * w, v, 2 * 0.001 * v}}};
}
INSTANTIATE_TEST_SUITE_P(Devices, UncertaintyImplicit,
                         ::testing::Values(ImplicitCase{"TableOneD1", model::PhantomTable1(), 1},
                                           ImplicitCase{"TableOneD2", model::PhantomTable1(), 2},
                                           ImplicitCase{"TableOneD4", model::PhantomTable1(), 4},
                                           ImplicitCase{"TableOneD8", model::PhantomTable1(), 8},
                                           ImplicitCase{"LightlyDampedD4", LightlyDamped(), 4, false}),
                         [](const ::testing::TestParamInfo<ImplicitCase>& i) { return std::string(i.param.name); });

// K_CR^max where the interval from K = 0+ closes (B_at_K_cr_max =
// B_max_from_zero: K_CR(B) rises to a corner there), on a device with a very
// lightly damped mode (zeta 0.001, 120 Hz pole over a 100 Hz zero) at d = 4:
// the delta method's std against Monte Carlo (it was 1e4 times too large when
// the perturbed search read K_CR just past the corner).
TEST(Uncertainty, DeltaMethodAtTheCornerWhereTheIntervalFromZeroCloses) {
  const double w = 2 * std::numbers::pi * 120, v = 2 * std::numbers::pi * 100;
  const model::Plant p{1e-3, 5e-3, {{w, 2 * 0.001 * w, v, 2 * 0.001 * v}}};
  const std::vector<double> cov = TestCovariance(p, 0.01, 7);
  const ZWidth z(p, 1e-3, 4);
  const DelaySummary s = z.Summarize();
  ASSERT_GT(s.B_at_K_cr_max, (1 - 1e-6) * s.B_max_from_zero);  // the corner
  const SummaryStd dm = SummaryStdDelta(p, cov, 1e-3, 4, s);
  const MonteCarloResult mc = SummaryMonteCarlo(p, cov, 1e-3, 4, 300, 13);
  EXPECT_LT(dm.K_cr_max / mc.std.K_cr_max, 1.5);
  EXPECT_GT(dm.K_cr_max / mc.std.K_cr_max, 1 / 1.5);
  std::printf("corner: delta %.4g monte carlo %.4g\n", dm.K_cr_max, mc.std.K_cr_max);
}

TEST(Uncertainty, RejectsABadCovariance) {
  const model::Plant p = model::PhantomTable1();
  EXPECT_THROW(CheckLogCovariance(p, {1.0, 0.0}), InputError);
  std::vector<double> c = TestCovariance(p, 0.01, 1);
  c[1] += 1.0;  // not symmetric
  EXPECT_THROW(CheckLogCovariance(p, c), InputError);
  const int n = NumLogParameters(p);
  std::vector<double> neg(n * n, 0.0);
  neg[0] = -1.0;
  EXPECT_THROW(CheckLogCovariance(p, neg), InputError);
}

// A log variance past kMaxLogVariance (an absolute covariance given as a
// relative one) is refused at the check, naming the parameter; the bound
// itself is accepted.
TEST(Uncertainty, RejectsALogVarianceBeyondTheBound) {
  const model::Plant p = model::PhantomTable1();
  const int n = NumLogParameters(p);
  const int last = n - 1;  // log(modes[N-1].d)
  std::vector<double> c(n * n, 0.0);
  for (int i = 0; i < n; ++i) c[i * n + i] = 1e-4;
  c[last * n + last] = kMaxLogVariance;
  EXPECT_NO_THROW(CheckLogCovariance(p, c));
  const std::string name = "log(modes[" + std::to_string(p.modes.size() - 1) + "].d)";
  for (double v : {std::nextafter(kMaxLogVariance, 1e300), 1e4, 1e300}) {
    c[last * n + last] = v;
    try {
      CheckLogCovariance(p, c);
      ADD_FAILURE() << "variance " << v << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

// Moved from haptic_loop_test.cc.
TEST(HapticLoop, KcrStdWithFilterAndHandMatchesFiniteDifferencesOfKcr) {
  // Implicit differentiation (stability/uncertainty.h) against K_CR(B)
  // recomputed on perturbed plants: J Sigma J^T with a seeded diagonal covariance.
  std::mt19937_64 rng(21);
  int compared = 0;
  for (int k = 0; k < 3; ++k) {
    const model::Plant p = test::RandomPlausibleDevice(rng, 1 + k);
    LoopOptions l;
    SetLowPassFilter(40.0 + 30.0 * k, 1e-3, &l);
    if (k > 0) l.hand = HandOf(k, p);
    const int d = 2 + 2 * k, np = NumLogParameters(p);
    std::vector<double> cov(np * np, 0.0), var(np);
    std::uniform_real_distribution<double> u(1e-5, 1e-3);
    for (int i = 0; i < np; ++i) cov[i * np + i] = var[i] = u(rng);
    const ZWidth z(p, 1e-3, d, l);
    const DelaySummary s = z.Summarize();
    std::vector<CriticalPoint> pts;
    for (double f : {0.0, 0.3, 0.6}) pts.push_back(z.At(f * s.B_max_from_zero));
    const std::vector<double> sd = KcrStd(p, cov, 1e-3, d, pts, {}, l);
    for (size_t j = 0; j < pts.size(); ++j) {
      if (!(pts[j].K_cr > 0 && std::isfinite(pts[j].K_cr))) continue;
      double v = 0.0;
      for (int i = 0; i < np; ++i) {
        std::vector<double> dx(np, 0.0);
        dx[i] = 1e-5;
        const double kp = ZWidth(PerturbLog(p, dx), 1e-3, d, l).At(pts[j].B).K_cr;
        dx[i] = -1e-5;
        const double km = ZWidth(PerturbLog(p, dx), 1e-3, d, l).At(pts[j].B).K_cr;
        const double g = (kp - km) / 2e-5;
        v += g * g * var[i];
      }
      EXPECT_NEAR(sd[j], std::sqrt(v), 1e-4 * std::sqrt(v)) << "k=" << k << " B=" << pts[j].B;
      ++compared;
    }
  }
  EXPECT_GE(compared, 6);
}

}  // namespace
}  // namespace zwidth::stability
