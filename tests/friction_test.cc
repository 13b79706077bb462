// model/friction.h: the actuator's limits against a brute force written here,
// and the friction's validation against its stated rules.
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "model/error.h"
#include "model/friction.h"

namespace zwidth::model {
namespace {

// Apply against a brute force: the multiple of the DAC step nearest u found
// by scanning k around u / step (ties to even, as nearbyint rounds), then
// clipped to [-saturation, saturation].
double BruteApply(double u, double step, double sat) {
  double v = u;
  if (step > 0.0) {
    const long k0 = static_cast<long>(std::floor(u / step)) - 2;
    double best = k0 * step;
    long best_k = k0;
    for (long k = k0; k <= k0 + 4; ++k) {
      const double d = std::abs(k * step - u), db = std::abs(best - u);
      if (d < db || (d == db && k % 2 == 0)) best = k * step, best_k = k;
    }
    v = best_k * step;
  }
  if (sat > 0.0) v = v > sat ? sat : v < -sat ? -sat : v;
  return v;
}

TEST(Actuator, ApplyIsTheNearestDacStepThenTheSaturation) {
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (const Actuator a : {Actuator{}, Actuator{1.5, 0.0}, Actuator{0.0, 0.01}, Actuator{0.71, 0.025}}) {
    for (int i = 0; i < 2000; ++i) {
      const double x = u(rng);
      EXPECT_NEAR(a.Apply(x), BruteApply(x, a.dac_step, a.saturation), 1e-15) << x;
    }
  }
  // Exact ties (a binary step): k + 1/2 steps round to the even multiple.
  const Actuator q{0.0, 0.25};
  EXPECT_EQ(q.Apply(0.125), 0.0);
  EXPECT_EQ(q.Apply(0.375), 0.5);
  EXPECT_EQ(q.Apply(-0.375), -0.5);
  EXPECT_TRUE(Actuator{}.IsZero());
  EXPECT_EQ(Actuator{}.Apply(-123.456), -123.456);
}

// The rules of Friction::IsValid from its header: levels finite, >= 0 and at
// most 1e12; the offset of any sign; a breakaway 0 or >= its Coulomb level.
TEST(Friction, ValidationFollowsTheStatedRulesAndNamesTheField) {
  std::string why;
  EXPECT_TRUE(Friction{}.IsValid(&why));
  EXPECT_TRUE(Friction::Symmetric(0.2).IsValid(&why));
  EXPECT_TRUE((Friction{0.1, 0.2, -5.0, 0.0, 0.0}.IsValid(&why)));     // offset of either sign
  EXPECT_TRUE((Friction{0.1, 0.2, 0.0, 0.1, 0.3}.IsValid(&why)));      // breakaway = or > the Coulomb level
  struct Bad { Friction f; const char* field; };
  const Bad bad[] = {
      {{-0.1, 0.0, 0.0, 0.0, 0.0}, "coulomb_pos"},
      {{0.0, std::nan(""), 0.0, 0.0, 0.0}, "coulomb_neg"},
      {{0.0, 0.0, 2e12, 0.0, 0.0}, "offset"},
      {{0.0, 0.0, std::numeric_limits<double>::infinity(), 0.0, 0.0}, "offset"},
      {{0.2, 0.0, 0.0, 0.1, 0.0}, "breakaway_pos"},  // below its Coulomb level
      {{0.0, 0.2, 0.0, 0.0, 0.19}, "breakaway_neg"},
      {{0.0, 0.0, 0.0, -1.0, 0.0}, "breakaway_pos"},
  };
  for (const Bad& b : bad) {
    why.clear();
    EXPECT_FALSE(b.f.IsValid(&why)) << b.field;
    EXPECT_EQ(why.rfind(std::string(b.field) + " =", 0), 0u) << why;
    EXPECT_THROW(b.f.Validate(), InputError) << b.field;
  }
  const Friction f{0.1, 0.3, 0.0, 0.0, 0.5};
  EXPECT_DOUBLE_EQ(f.MeanCoulomb(), 0.2);
  EXPECT_DOUBLE_EQ(f.StaticPos(), 0.1);  // 0 = the Coulomb level
  EXPECT_DOUBLE_EQ(f.StaticNeg(), 0.5);
  std::string a_why;
  EXPECT_FALSE((Actuator{-1.0, 0.0}.IsValid(&a_why)));
}

}  // namespace
}  // namespace zwidth::model
