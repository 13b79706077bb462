// model/state_space.h: the continuous realisation and its exact ZOH (moved from
// model_test.cc, tests unchanged; new tests below the moved ones).
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"
#include "model/zoh_modal.h"

namespace zwidth {
namespace {

using cd = std::complex<double>;

TEST(Plant, StateSpaceRealisesTheFactoredFormula) {
  const model::Plant p = model::PhantomTable1();
  const model::StateSpace ss = model::ContinuousStateSpace(p);
  for (double f : {0.3, 5.0, 66.0, 76.0, 87.0, 184.0, 450.0, 3000.0}) {
    const double w = 2 * std::numbers::pi * f;
    Eigen::MatrixXcd M = cd(0, w) * Eigen::MatrixXcd::Identity(6, 6) - ss.A.cast<cd>();
    const cd g = (ss.C.cast<cd>() * M.partialPivLu().solve(ss.B.cast<cd>()))(0) + ss.D;
    // Factored formula written out here, independently of ContinuousResponse.
    const cd s(0, w);
    cd ref = 1.0 / (1.168e-3 * s * s + 0.00584 * s);
    ref *= (479.166 * 479.166) / (417.612 * 417.612) * (s * s + 80.0 * s + 417.612 * 417.612) /
               (s * s + 83.0 * s + 479.166 * 479.166);
    ref *= (1159.31 * 1159.31) / (546.626 * 546.626) * (s * s + 90.0 * s + 546.626 * 546.626) /
           (s * s + 352.0 * s + 1159.31 * 1159.31);
    EXPECT_LT(std::abs(g - ref) / std::abs(ref), 1e-12) << f;
    EXPECT_LT(std::abs(model::ContinuousResponse(p, w) - ref) / std::abs(ref), 1e-14) << f;
  }
}

// RK4 with 2000 sub-steps per period, input held: the reference for the ZOH.
Eigen::VectorXd Rk4Step(const model::StateSpace& c, const Eigen::VectorXd& x0, double u, double T, int steps) {
  Eigen::VectorXd x = x0;
  const double h = T / steps;
  auto f = [&](const Eigen::VectorXd& s) { Eigen::VectorXd d = c.A * s + c.B * u; return d; };
  for (int i = 0; i < steps; ++i) {
    const Eigen::VectorXd k1 = f(x), k2 = f(x + 0.5 * h * k1), k3 = f(x + 0.5 * h * k2), k4 = f(x + h * k3);
    x += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return x;
}

TEST(Zoh, EqualsFineStepSimulationOfTheContinuousPlantUnderAHeldInput) {
  const model::Plant p = model::PhantomTable1();
  const double T = 1e-3;
  const model::StateSpace c = model::ContinuousStateSpace(p), d = model::DiscretizeZoh(p, T);
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 0.03);
  std::vector<double> u(200);
  for (double& v : u) v = n(rng);
  const std::vector<double> yd = model::SimulateDiscrete(d, u);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(6);
  double max_err = 0, max_y = 0;
  for (size_t k = 0; k < u.size(); ++k) {
    const double y = c.C.dot(x);
    max_err = std::max(max_err, std::abs(y - yd[k]));
    max_y = std::max(max_y, std::abs(y));
    x = Rk4Step(c, x, u[k], T, 2000);
  }
  EXPECT_LT(max_err / max_y, 1e-9);
}

class ZohPeriods : public ::testing::TestWithParam<double> {};

TEST_P(ZohPeriods, ModalFormEqualsStateSpaceResponse) {
  const model::Plant p = model::PhantomTable1();
  const double T = GetParam();
  const model::DiscreteResponse r(model::DiscretizeZoh(p, T));
  model::ZohModalForm<double> f;
  std::vector<double> sec;
  for (const model::Mode& m : p.modes) { sec.insert(sec.end(), {m.omega, m.c, m.v, m.d}); }
  ASSERT_TRUE(f.Build(p.m, p.b, sec.data(), 2, T));
  for (double th = 0.001; th < 3.14; th += 0.0137) {
    const cd a = r.AtTheta(th);
    const model::Cx<double> b = f.At(std::cos(th), std::sin(th));
    // Both exact: they agree to round-off (a badly balanced realisation lost
    // 4 digits here before the rigid states were scaled by m).
    EXPECT_LT(std::abs(a - cd(b.re, b.im)) / std::abs(a), 1e-11) << T << " " << th;
  }
}

INSTANTIATE_TEST_SUITE_P(Periods, ZohPeriods, ::testing::Values(1e-3, 5e-4, 1e-4),
                         [](const ::testing::TestParamInfo<double>& i) {
                           return "T" + std::to_string(std::lround(i.param * 1e6)) + "us";
                         });

TEST(Zoh, RigidBodyMatchesTheClosedForm) {
  // The double-integrator limit (b -> 0) of the rigid body has the closed
  // form ZOH T^2 (z + 1) / (2 m (z - 1)^2).
  model::Plant p;
  p.m = 2.0;
  p.b = 1e-9;
  const double T = 0.01;
  const model::DiscreteResponse r(model::DiscretizeZoh(p, T));
  for (double th : {0.01, 0.3, 1.0, 2.5}) {
    const cd z = std::polar(1.0, th);
    const cd ref = T * T * (z + 1.0) / (2.0 * p.m * (z - 1.0) * (z - 1.0));
    EXPECT_LT(std::abs(r.AtZ(z) - ref) / std::abs(ref), 1e-6) << th;
  }
}

// ---- New tests (issue 24 must-have 6).

// A random stable discrete system of order n: A = Q diag-blocks Q^-1 with
// eigenvalues of modulus < 0.95 (seeded), B, C, D random.
model::StateSpace RandomDiscrete(std::mt19937_64& rng, int n, int delay) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) M(i, i) = 0.9 * u(rng);
  for (int i = 0; i + 1 < n; i += 2) M(i, i + 1) = 0.4 * u(rng), M(i + 1, i) = -M(i, i + 1), M(i + 1, i + 1) = M(i, i);
  Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i < n; ++i) for (int j = 0; j < n; ++j) Q(i, j) += 0.3 * u(rng);
  model::StateSpace s;
  s.A = Q * M * Q.inverse();
  s.B = Eigen::VectorXd::NullaryExpr(n, [&] { return u(rng); });
  s.C = Eigen::RowVectorXd::NullaryExpr(n, [&] { return u(rng); });
  s.D = u(rng);
  s.period_s = 1e-3;
  s.delay_samples = delay;
  return s;
}

// The recursion x_{k+1} = A x_k + B u_{k-d}, y_k = C x_k + D u_{k-d} from
// rest, written out here: the reference for SimulateDiscrete.
std::vector<double> Recursion(const model::StateSpace& s, const std::vector<double>& u) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(s.A.rows());
  std::vector<double> y;
  for (size_t k = 0; k < u.size(); ++k) {
    const double uk = k >= static_cast<size_t>(s.delay_samples) ? u[k - s.delay_samples] : 0.0;
    y.push_back(s.C.dot(x) + s.D * uk);
    x = (s.A * x + s.B * uk).eval();
  }
  return y;
}

// DiscreteResponse (a Hessenberg solve after balancing) against a dense LU
// solve of C (zI - A)^-1 B + D, times z^-delay, on random systems.
TEST(StateSpace, DiscreteResponseIsTheDenseTransferFunction) {
  std::mt19937_64 rng(24);
  for (int k = 0; k < 10; ++k) {
    const model::StateSpace s = RandomDiscrete(rng, 2 + k, k % 4);
    const model::DiscreteResponse r(s);
    EXPECT_EQ(r.delay_samples(), k % 4);
    for (double th : {0.003, 0.4, 1.7, 3.1}) {
      const cd z = std::polar(1.0, th);
      const Eigen::MatrixXcd M = z * Eigen::MatrixXcd::Identity(s.A.rows(), s.A.cols()) - s.A.cast<cd>();
      const cd g = (s.C.cast<cd>() * M.partialPivLu().solve(s.B.cast<cd>()))(0) + s.D;
      EXPECT_LT(std::abs(r.AtZ(z) - g), 1e-11 * (1 + std::abs(g))) << k << " " << th;
      const cd want = g * std::pow(z, -s.delay_samples);
      EXPECT_LT(std::abs(r.AtTheta(th) - want), 1e-11 * (1 + std::abs(g))) << k << " " << th;
    }
  }
}

// SimulateDiscrete and the same system with its delay as states
// (WithDelayStates, delay 0) against the recursion written above, with a
// feedthrough D != 0 and delays 0..3.
TEST(StateSpace, SimulationWithTheDelayAsStatesIsTheDelayedRecursion) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<double> u(200);
  for (double& v : u) v = g(rng);
  for (int d = 0; d <= 3; ++d) {
    const model::StateSpace s = RandomDiscrete(rng, 4, d);
    const std::vector<double> want = Recursion(s, u);
    const std::vector<double> got = model::SimulateDiscrete(s, u);
    const model::StateSpace w = model::WithDelayStates(s);
    EXPECT_EQ(w.delay_samples, 0);
    EXPECT_EQ(w.A.rows(), s.A.rows() + d);
    const std::vector<double> aug = model::SimulateDiscrete(w, u);
    ASSERT_EQ(got.size(), u.size());
    ASSERT_EQ(aug.size(), u.size());
    for (size_t k = 0; k < u.size(); ++k) {
      EXPECT_NEAR(got[k], want[k], 1e-12 * (1 + std::abs(want[k]))) << "d = " << d << " k = " << k;
      EXPECT_NEAR(aug[k], want[k], 1e-12 * (1 + std::abs(want[k]))) << "delay states, d = " << d << " k = " << k;
    }
  }
}

// The ZOH of a diagonalisable continuous system A = V diag(l) V^-1 in closed
// form: Ad = V diag(e^{l T}) V^-1 and Bd = V diag((e^{l T} - 1)/l) V^-1 B
// (the integral of e^{A s} B over one period), against DiscretizeZoh's Van Loan.
TEST(StateSpace, ZohOfADiagonalisableSystemIsTheEigenvalueClosedForm) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 6; ++k) {
    const int n = 2 + k;
    Eigen::VectorXd l(n);
    for (int i = 0; i < n; ++i) l(i) = -std::pow(10.0, 1.0 + 2.5 * (u(rng) + 1.0) / 2.0);  // -10 .. -3000 /s
    Eigen::MatrixXd V = Eigen::MatrixXd::Identity(n, n);
    for (int i = 0; i < n; ++i) for (int j = 0; j < n; ++j) V(i, j) += 0.4 * u(rng);
    const Eigen::MatrixXd Vi = V.inverse();
    model::StateSpace c;
    c.A = V * l.asDiagonal() * Vi;
    c.B = Eigen::VectorXd::NullaryExpr(n, [&] { return u(rng); });
    c.C = Eigen::RowVectorXd::NullaryExpr(n, [&] { return u(rng); });
    const double T = 1e-3;
    const model::StateSpace d = model::DiscretizeZoh(c, T);
    Eigen::VectorXd e(n), q(n);
    for (int i = 0; i < n; ++i) e(i) = std::exp(l(i) * T), q(i) = std::expm1(l(i) * T) / l(i);
    const Eigen::MatrixXd Ad = V * e.asDiagonal() * Vi;
    const Eigen::VectorXd Bd = V * q.asDiagonal() * Vi * c.B;
    EXPECT_LT((d.A - Ad).norm(), 1e-12 * Ad.norm()) << n;
    EXPECT_LT((d.B - Bd).norm(), 1e-12 * Bd.norm()) << n;
    EXPECT_EQ(d.C, c.C);
    EXPECT_DOUBLE_EQ(d.period_s, T);
  }
}

TEST(StateSpace, ZohRefusesAPeriodThatIsNotFiniteAndPositive) {
  const model::Plant p = model::PhantomTable1();
  for (double T : {0.0, -1e-3, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(model::DiscretizeZoh(p, T), InputError) << T;
  }
}

}  // namespace
}  // namespace zwidth
