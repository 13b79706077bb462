// fit/residual.cc (the weighted ZOH residual, its Jacobian, the covariance)
// against independent references:
// - the residuals against w_k (H_k - G(z_k) z_k^-D) with G the ZOH response of
//   the state space (model/state_space.h: Van Loan and a Hessenberg solve),
//   not the pole-residue form the residual uses;
// - the analytic Jacobian (ceres::Jet on the pole-residue coefficients)
//   against central differences of those residuals;
// - the covariance against (J^T J)^-1 by a Cholesky solve;
// - FromLog(ToLog(p)) = p.
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "fit/fit_internal.h"
#include "model/plant.h"
#include "model/state_space.h"

namespace zwidth::fit::internal {
namespace {

// Bins of a seeded noisy response of `truth` at 1 kHz, delay D, 3..400 Hz.
Bins MakeTestBins(const model::Plant& truth, int D, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.5, 2.0);
  const double T = 1e-3;
  model::Plant t = truth;
  t.delay_samples = D;
  const model::DiscreteResponse r(model::DiscretizeZoh(t, T));
  Bins b;
  b.period_s = T;
  for (double f = 3.0; f <= 400.0; f += 3.0) {
    const double th = 2 * std::numbers::pi * f * T;
    const cd H = r.AtTheta(th);
    const double s = 0.02 * std::abs(H) * u(rng);
    b.z.push_back(std::polar(1.0, th));
    b.delay.push_back(std::polar(1.0, -th * D));
    b.H.push_back(H + s * cd(g(rng), g(rng)));
    b.weight.push_back(1.0 / s);
  }
  return b;
}

// The plant the residual is evaluated at: the truth moved by a few per cent.
model::Plant Moved(const model::Plant& p) {
  model::Plant q = p;
  q.m *= 1.03;
  q.b *= 0.9;
  for (model::Mode& md : q.modes) md.omega *= 1.02, md.c *= 1.1, md.v *= 0.98, md.d *= 0.95;
  return q;
}

TEST(Residual, IsTheWeightedMisfitOfTheStateSpaceZoh) {
  for (int D : {0, 2}) {
    const model::Plant truth = model::PhantomTable1();
    const Bins b = MakeTestBins(truth, D, 1 + D);
    const model::Plant at = Moved(truth);
    const int n = static_cast<int>(at.modes.size());
    std::vector<double> cov;
    Eigen::VectorXd r;
    ASSERT_TRUE(LogCovariance(b, n, ToLog(at), &cov, nullptr, &r));
    const model::DiscreteResponse g(model::DiscretizeZoh(at, b.period_s));
    ASSERT_EQ(r.size(), 2 * static_cast<Eigen::Index>(b.z.size()));
    for (size_t k = 0; k < b.z.size(); ++k) {
      const cd want = b.weight[k] * (b.H[k] - g.AtZ(b.z[k]) * b.delay[k]);
      EXPECT_NEAR(r(2 * k), want.real(), 1e-8 * (1 + std::abs(want))) << "D " << D << " bin " << k;
      EXPECT_NEAR(r(2 * k + 1), want.imag(), 1e-8 * (1 + std::abs(want))) << "D " << D << " bin " << k;
    }
  }
}

TEST(Residual, JacobianIsTheCentralDifferenceOfTheResiduals) {
  const model::Plant truth = model::PhantomTable1();
  const Bins b = MakeTestBins(truth, 1, 7);
  const model::Plant at = Moved(truth);
  const int n = static_cast<int>(at.modes.size());
  const std::vector<double> x = ToLog(at);
  std::vector<double> cov;
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  ASSERT_TRUE(LogCovariance(b, n, x, &cov, &J, &r));
  ASSERT_EQ(J.cols(), static_cast<Eigen::Index>(x.size()));
  const double h = 1e-6;
  for (size_t q = 0; q < x.size(); ++q) {
    std::vector<double> xp = x, xm = x, c2;
    xp[q] += h;
    xm[q] -= h;
    Eigen::VectorXd rp, rm;
    ASSERT_TRUE(LogCovariance(b, n, xp, &c2, nullptr, &rp));
    ASSERT_TRUE(LogCovariance(b, n, xm, &c2, nullptr, &rm));
    const Eigen::VectorXd fd = (rp - rm) / (2 * h);
    EXPECT_LT((J.col(q) - fd).norm(), 1e-6 * fd.norm()) << "parameter " << q;
  }
  // The covariance is (J^T J)^-1.
  const int p = static_cast<int>(x.size());
  const Eigen::MatrixXd want = (J.transpose() * J).ldlt().solve(Eigen::MatrixXd::Identity(p, p));
  const Eigen::MatrixXd got = Eigen::Map<const Eigen::MatrixXd>(cov.data(), p, p);
  EXPECT_LT((got - want).norm(), 1e-8 * want.norm());
}

TEST(Residual, LogParametersRoundTrip) {
  const model::Plant p = Moved(model::PhantomTable1());
  const std::vector<double> x = ToLog(p);
  ASSERT_EQ(x.size(), 2 + 4 * p.modes.size());
  EXPECT_NEAR(x[0], std::log(p.m), 0.0);
  EXPECT_NEAR(x[3], std::log(p.modes[0].c / (2 * p.modes[0].omega)), 1e-15);  // log damping ratio
  const model::Plant q = FromLog(x, static_cast<int>(p.modes.size()));
  EXPECT_NEAR(q.m, p.m, 1e-15 * p.m);
  EXPECT_NEAR(q.b, p.b, 1e-15 * p.b);
  for (size_t i = 0; i < p.modes.size(); ++i) {
    EXPECT_NEAR(q.modes[i].omega, p.modes[i].omega, 1e-13 * p.modes[i].omega);
    EXPECT_NEAR(q.modes[i].c, p.modes[i].c, 1e-13 * p.modes[i].c);
    EXPECT_NEAR(q.modes[i].v, p.modes[i].v, 1e-13 * p.modes[i].v);
    EXPECT_NEAR(q.modes[i].d, p.modes[i].d, 1e-13 * p.modes[i].d);
  }
}

// Fewer residuals than parameters: no covariance.
TEST(Residual, TooFewBinsGiveNoCovariance) {
  Bins b = MakeTestBins(model::PhantomTable1(), 0, 3);
  b.z.resize(2), b.delay.resize(2), b.H.resize(2), b.weight.resize(2);
  std::vector<double> cov;
  EXPECT_FALSE(LogCovariance(b, 2, ToLog(model::PhantomTable1()), &cov));
}

}  // namespace
}  // namespace zwidth::fit::internal
