#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>

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

TEST(Plant, ValidationNamesTheParameter) {
  model::Plant p = model::PhantomTable1();
  p.modes[1].c = -3;
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("modes[1].c"), std::string::npos) << why;
  p = model::PhantomTable1();
  p.m = std::nan("");
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("m = "), std::string::npos);
  EXPECT_THROW(model::DiscretizeZoh(model::PhantomTable1(), 0.0), InputError);
}

}  // namespace
}  // namespace zwidth
