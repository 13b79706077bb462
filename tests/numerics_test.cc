// stability/numerics_internal.h: the shared numerical kernels against known
// answers: roots of equations whose roots are known in closed form (cbrt 2,
// the Dottie number cos x = x to 16 digits, pi), extrema at known points,
// the polynomial product against the product of evaluations at random points
// (p q)(x) = p(x) q(x), and the count propagation against its stated rules.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "stability/numerics_internal.h"

namespace zwidth::stability::internal {
namespace {

TEST(Numerics, BrentRootFindsClosedFormRoots) {
  auto cube = [](double x) { return x * x * x - 2.0; };
  EXPECT_NEAR(BrentRoot(cube, 0.0, 3.0, cube(0.0), cube(3.0), 1e-15), std::cbrt(2.0), 4e-16);
  auto dottie = [](double x) { return std::cos(x) - x; };
  EXPECT_NEAR(BrentRoot(dottie, 0.0, 1.0, dottie(0.0), dottie(1.0), 1e-15), 0.7390851332151607, 4e-16);
  auto sine = [](double x) { return std::sin(x); };
  EXPECT_NEAR(BrentRoot(sine, 2.0, 4.5, sine(2.0), sine(4.5), 1e-14), std::numbers::pi, 1e-14);
  // A root at an end of the bracket is that end.
  auto line = [](double x) { return x - 1.0; };
  EXPECT_EQ(BrentRoot(line, 1.0, 2.0, 0.0, 1.0, 1e-12), 1.0);
  EXPECT_EQ(BrentRoot(line, 0.0, 1.0, -1.0, 0.0, 1e-12), 1.0);
}

TEST(Numerics, ExtremaAreAtTheirKnownPoints) {
  auto s = [](double x) { return std::sin(x); };
  auto q = [](double x) { return (x - 1.3) * (x - 1.3) + 2.0; };
  const double tol = 1e-9;
  // sin's maximum at pi/2: f is flat there, so x is only known to sqrt(eps f).
  EXPECT_NEAR(BrentExtremum(s, 0.0, 3.0, +1.0, tol), std::numbers::pi / 2, 1e-7);
  EXPECT_NEAR(GoldenExtremum(s, 0.0, 3.0, +1.0, tol), std::numbers::pi / 2, 1e-7);
  EXPECT_NEAR(BrentExtremum(q, -4.0, 5.0, -1.0, tol), 1.3, 1e-7);
  EXPECT_NEAR(GoldenExtremum(q, -4.0, 5.0, -1.0, tol), 1.3, 1e-7);
  // At an end of the bracket when f is monotone there.
  auto up = [](double x) { return x; };
  EXPECT_NEAR(BrentExtremum(up, 0.0, 1.0, +1.0, tol), 1.0, 1e-6);
  EXPECT_NEAR(GoldenExtremum(up, 0.0, 1.0, -1.0, tol), 0.0, 1e-6);
}

TEST(Numerics, PolyMulIsTheProductOfTheEvaluations) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto eval = [](const std::vector<double>& p, double x) {
    double v = 0.0, xk = 1.0;
    for (double c : p) v += c * xk, xk *= x;
    return v;
  };
  for (int k = 0; k < 20; ++k) {
    std::vector<double> a(1 + k % 5), b(1 + k % 7);
    for (double& c : a) c = u(rng);
    for (double& c : b) c = u(rng);
    const std::vector<double> r = PolyMul(a, b);
    ASSERT_EQ(r.size(), a.size() + b.size() - 1);
    for (double x : {-1.3, -0.4, 0.0, 0.7, 1.9}) {
      EXPECT_NEAR(eval(r, x), eval(a, x) * eval(b, x), 1e-12 * (1 + std::abs(eval(a, x) * eval(b, x)))) << k << " " << x;
    }
  }
}

// PropagateCount(s) from their header: count + change inside [0, order], else
// or when anything is unknown -1; counts between two direct counts only when
// every step is known and the last reaches the next direct count.
TEST(Numerics, CountPropagationFollowsItsRules) {
  EXPECT_EQ(PropagateCount(2, +2, true, 6), 4);
  EXPECT_EQ(PropagateCount(2, -2, true, 6), 0);
  EXPECT_EQ(PropagateCount(2, -3, true, 6), -1);  // below 0
  EXPECT_EQ(PropagateCount(5, +2, true, 6), -1);  // above the order
  EXPECT_EQ(PropagateCount(2, +2, false, 6), -1); // the direction lost
  EXPECT_EQ(PropagateCount(-1, +2, true, 6), -1); // the count not known
  std::vector<int> c;
  EXPECT_TRUE(PropagateCounts(0, 2, {+2, -2, +2}, 6, &c));
  EXPECT_EQ(c, (std::vector<int>{2, 0}));
  EXPECT_FALSE(PropagateCounts(0, 4, {+2, -2, +2}, 6, &c));  // reaches 2, not 4
  EXPECT_TRUE(c.empty());
  EXPECT_FALSE(PropagateCounts(0, 2, {+2, 0, 0}, 6, &c));    // a step not known
  EXPECT_TRUE(c.empty());
  EXPECT_TRUE(PropagateCounts(3, 3, {}, 6, &c));
  EXPECT_TRUE(c.empty());
}

}  // namespace
}  // namespace zwidth::stability::internal
