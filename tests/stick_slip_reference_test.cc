// StickSlipPlant (model/nonlinear_simulate.h) against a brute force that shares
// none of its method (tests/stick_slip_reference.h: RK4 at T / 1000, the
// switches found per substep by bisection), on seeded random cases.
//
// How the cases are made: case i draws from std::mt19937_64(1000 + i), in this
// order: the plant (i % 3 == 0 the rigid body of Table I, 1 Table I itself,
// 2 RandomPlausibleDevice with 1 + (i / 3) % 2 modes: 30-400 Hz, damping
// ratios 0.002-0.3); a Coulomb level F_c = U(0.02, 0.30) x the torque rms;
// coulomb_neg = F_c U(0.7, 1.3) on odd i / 3 (else = F_c); a breakaway level
// U(1, 1.5) x each Coulomb level when i % 4 >= 2; an offset U(-0.5, 0.5) F_c
// when i % 5 >= 3; then 1500 samples at 1 kHz of white Gaussian torque of
// rms 0.03 N m (the rigid body and Table I) or 0.03 N m x m / 1.168e-3 (a
// random device, so that it moves as far), held over each period.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "model/nonlinear_simulate.h"
#include "model/plant.h"
#include "model/state_space.h"
#include "tests/stick_slip_reference.h"
#include "tests/test_util.h"

namespace zwidth::model {
namespace {

constexpr double kT = 1e-3;
constexpr int kReferenceSubsteps = 1000;

struct RandomCase {
  Plant plant;
  Friction friction;
  std::vector<double> torque;
  std::string what;
};

RandomCase MakeCase(int i) {
  std::mt19937_64 rng(1000 + i);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  RandomCase c;
  const Plant table1 = PhantomTable1();
  switch (i % 3) {
    case 0: c.plant = Plant{table1.m, table1.b, {}, 0, "rigid"}; break;
    case 1: c.plant = table1; break;
    default: c.plant = test::RandomPlausibleDevice(rng, 1 + (i / 3) % 2); break;
  }
  const double rms = 0.03 * (i % 3 == 2 ? c.plant.m / table1.m : 1.0);
  const double fc = rms * (0.02 + 0.28 * U(rng));
  c.friction = Friction::Symmetric(fc);
  if ((i / 3) % 2 == 1) c.friction.coulomb_neg = fc * (0.7 + 0.6 * U(rng));
  if (i % 4 >= 2) {
    c.friction.breakaway_pos = c.friction.coulomb_pos * (1.0 + 0.5 * U(rng));
    c.friction.breakaway_neg = c.friction.coulomb_neg * (1.0 + 0.5 * U(rng));
  }
  if (i % 5 >= 3) c.friction.offset = fc * (U(rng) - 0.5);
  std::normal_distribution<double> normal(0.0, rms);
  c.torque.resize(1500);
  for (double& u : c.torque) u = normal(rng);
  char buf[200];
  std::snprintf(buf, sizeof buf, "case %d (%s, %zu modes, F_c %.3g/%.3g of rms, breakaway %.3g/%.3g, offset %.3g)", i,
                c.plant.name.c_str(), c.plant.modes.size(), c.friction.coulomb_pos / rms, c.friction.coulomb_neg / rms,
                c.friction.breakaway_pos / rms, c.friction.breakaway_neg / rms, c.friction.offset / rms);
  c.what = buf;
  return c;
}

struct Comparison {
  double max_error = 0.0;  // largest |position difference| over the samples
  double range = 0.0;      // of the reference's positions
  size_t first_bad = 0;    // first sample differing by more than 1e-9 of the range
  int64_t switches = 0;    // the simulator's
};

Comparison Compare(const RandomCase& c) {
  const StateSpace ss = ContinuousStateSpace(c.plant);
  const std::vector<double> ref = testing::StickSlipReferenceLog(ss, c.friction, c.torque, kT, kReferenceSubsteps);
  StickSlipPlant s(ss, c.friction, kT);
  Comparison r;
  r.range = *std::max_element(ref.begin(), ref.end()) - *std::min_element(ref.begin(), ref.end());
  r.first_bad = ref.size();
  for (size_t k = 0; k < ref.size(); ++k) {
    const double e = std::abs(s.position() - ref[k]);
    r.max_error = std::max(r.max_error, e);
    if (e > 1e-9 * r.range && r.first_bad == ref.size()) r.first_bad = k;
    s.Step(c.torque[k]);
  }
  r.switches = s.switches();
  return r;
}

// The reference itself on closed forms of a rigid body m v' = u - F_c - b v:
// a kick of one period, then sliding to rest at t_s = (m/b) ln(1 + b v1/F_c),
// y_s = y1 + (m/b)(v1 + F_c/b)(1 - e^{-b t_s/m}) - F_c t_s/b, and no motion after.
TEST(StickSlipReference, BruteForceStopsWhereTheClosedFormSays) {
  const Plant p{1.168e-3, 5.84e-3, {}, 0, "rigid"};
  const double m = p.m, b = p.b, fc = 0.01;
  testing::StickSlipReference r(ContinuousStateSpace(p), Friction::Symmetric(fc), kT, kReferenceSubsteps);
  r.Step(0.3);
  const double y1 = r.position(), v1 = r.velocity();
  EXPECT_NEAR(v1, (0.3 - fc) / b * (1.0 - std::exp(-b * kT / m)), 1e-10 * v1);
  const double ts = m / b * std::log(1.0 + b * v1 / fc);
  const double ys = y1 + m / b * (v1 + fc / b) * (1.0 - std::exp(-b * ts / m)) - fc * ts / b;
  for (int k = 0; k < 100; ++k) r.Step(0.0);
  EXPECT_NEAR(r.position(), ys, 1e-10 * ys);
  EXPECT_EQ(r.velocity(), 0.0);
  EXPECT_EQ(r.switches(), 2);
}

// Every case within 1e-9 of its range of the brute force (which itself is
// good to ~1e-14 rad here: at T/1000 and T/3000 it agrees to 1e-14 rad on
// cases 1, 5 and 8). Measured before the fix (2026-12-03): 14 of the 24 cases
// off by more than 1e-9 of the range, 13 by more than 1e-6, worst 8.7e-2.
TEST(StickSlipReference, RandomCasesAgreeWithTheBruteForce) {
  constexpr int kCases = 24;
  int bad = 0;
  double worst = 0.0;
  for (int i = 0; i < kCases; ++i) {
    const RandomCase c = MakeCase(i);
    const Comparison r = Compare(c);
    ASSERT_GT(r.switches, 10) << c.what;  // stick-slip happened
    const double rel = r.max_error / r.range;
    worst = std::max(worst, rel);
    std::printf("%s: switches %lld, max |dy| %.3g rad = %.3g of the range%s\n", c.what.c_str(),
                static_cast<long long>(r.switches), r.max_error, rel,
                r.first_bad < c.torque.size() ? (", first off at sample " + std::to_string(r.first_bad)).c_str() : "");
    bad += rel > 1e-9;
    EXPECT_LT(rel, 1e-9) << c.what;
  }
  std::printf("%d of %d cases off by more than 1e-9 of the range; worst %.3g\n", bad, kCases, worst);
}

// A reversal and return inside one cell that neither the cell's ends nor
// their accelerations show. Table I sliding (v > 0) under a held torque, from a
// state chosen so that v(t) = v0 + a0 t + j0 t^2/2 + s0 t^3/6 (v^(4) = 0 at
// t = 0): a(t) = (s0/2)(t - t1)(t - t2) with t1 = 50 us, t2 = 200 us, so v
// rises, dips to v(t2) = -v0 and rises again, all inside one cell, with a(0) > 0
// and a(h) > 0. The body must stop at the dip's first zero (the brute force
// does) and then stick or reverse. Before the fix the simulator slid through
// it (4 switches in 20 periods against 6, 4.9e-9 rad off).
TEST(StickSlipReference, ReversalAndReturnInsideOneCellIsFound) {
  const Plant p = PhantomTable1();
  const StateSpace ss = ContinuousStateSpace(p);
  const Friction f = Friction::Symmetric(0.002);
  const double u = 0.001, u_p = u - f.coulomb_pos;  // sliding with v > 0
  const double t1 = 50e-6, t2 = 200e-6, a0 = 0.1;
  const double s0 = 2.0 * a0 / (t1 * t2), j0 = -0.5 * s0 * (t1 + t2);
  const double v0 = 0.5 * (0.5 * s0 * t2 * t2 * (t2 / 6.0 - t1 / 2.0));  // half the dip's depth
  // v^(k)(0) = C A^(k+1) x + C A^k B u_p (k >= 1), v(0) = C A x: five
  // equations in the five states other than the position (state n - 2, which
  // v does not see), each row scaled to norm 1.
  const int n = static_cast<int>(ss.A.rows());
  ASSERT_EQ(n, 6);
  const int m = n - 1, kPosition = n - 2;
  Eigen::MatrixXd O(m, m);
  Eigen::VectorXd rhs(m);
  const double target[5] = {v0, a0, j0, s0, 0.0};
  Eigen::RowVectorXd prev = ss.C, row = ss.C * ss.A;  // C A^k, C A^(k+1)
  for (int k = 0; k < m; ++k) {
    Eigen::RowVectorXd reduced(m);
    for (int j = 0, c = 0; j < n; ++j) {
      if (j != kPosition) reduced(c++) = row(j);
    }
    const double norm = reduced.norm();
    O.row(k) = reduced / norm;
    rhs(k) = (target[k] - (k == 0 ? 0.0 : prev.dot(ss.B) * u_p)) / norm;
    prev = row;
    row = row * ss.A;
  }
  const Eigen::VectorXd xr = O.colPivHouseholderQr().solve(rhs);
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
  for (int j = 0, c = 0; j < n; ++j) {
    if (j != kPosition) x0(j) = xr(c++);
  }
  StickSlipPlant s(ss, f, kT);
  s.Reset(x0);
  testing::StickSlipReference r(ss, f, kT, 4000);
  r.Reset(x0);
  ASSERT_GT(s.velocity(), 0.0);
  // The brute force's path over the first cell: the dip is there.
  double v_min = 1.0;
  for (int k = 1; k <= 333; ++k) {
    const StateSpace d = DiscretizeZoh(ss, k * 1e-6);
    v_min = std::min(v_min, (ss.C * ss.A).dot(d.A * x0 + d.B * u_p));
  }
  std::printf("v0 %.3g, dip's minimum %.3g rad/s (the cubic's %.3g)\n", v0, v_min, -v0);
  ASSERT_LT(v_min, 0.0);
  // The premise: the dip lies inside the first cell, 1/16 of the fastest period
  // of the moving and the stuck dynamics (as the header says), or the period/2.
  const Eigen::MatrixXd As = ss.A - ss.B * (ss.C * ss.A * ss.A) / (ss.C * ss.A).dot(ss.B);
  const double rho = std::max(Eigen::EigenSolver<Eigen::MatrixXd>(ss.A).eigenvalues().cwiseAbs().maxCoeff(),
                              Eigen::EigenSolver<Eigen::MatrixXd>(As).eigenvalues().cwiseAbs().maxCoeff());
  const double cell = std::min(kT / 2, 2 * std::numbers::pi / rho / 16);
  std::printf("cell <= %.3g us\n", 1e6 * cell);
  ASSERT_LT(t2, cell);
  double e = 0.0;
  for (int k = 0; k < 20; ++k) {
    s.Step(u);
    r.Step(u);
    e = std::max(e, std::abs(s.position() - r.position()));
  }
  std::printf("switches: simulator %lld, brute force %lld; max |dy| over 20 periods %.3g rad\n",
              static_cast<long long>(s.switches()), static_cast<long long>(r.switches()), e);
  EXPECT_GT(r.switches(), 0);
  EXPECT_EQ(s.switches(), r.switches());
  EXPECT_LT(e, 1e-12);
}

}  // namespace
}  // namespace zwidth::model
