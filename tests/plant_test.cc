// model/plant.h: eq. (1)'s plant, its validation and its response.
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "model/state_space.h"

namespace zwidth {
namespace {

// Moved from model_test.cc (unchanged).
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

// ---- New tests (issue 24 must-have 6): ContinuousResponse against exact
// limits and an identity of eq. (1), not against its own formula.

// The rigid body alone is 1/(m s^2 + b s) at s = j w, written out in real and
// imaginary parts: -m/(m^2 w^2 + b^2) and -b/(w (m^2 w^2 + b^2)).
TEST(Plant, RigidBodyIsItsClosedForm) {
  model::Plant p;
  p.m = 2.5e-3;
  p.b = 7e-3;
  for (double w : {0.1, 3.0, 100.0, 6000.0}) {
    const double den = p.m * p.m * w * w + p.b * p.b;
    const std::complex<double> want(-p.m / den, -p.b / (w * den));
    EXPECT_LT(std::abs(model::ContinuousResponse(p, w) - want), 1e-14 * std::abs(want)) << w;
  }
}

// Eq. (1) is a product: G(p with sections S1 and S2) = G(p with S1) G(p with
// S2) / G(rigid body), for seeded random sections (catches a section read
// with another's parameters or applied twice).
TEST(Plant, SectionsMultiply) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto section = [&] {
    const double w = 2 * std::numbers::pi * (20 + 400 * u(rng)), v = w * (0.5 + u(rng));
    return model::Mode{w, 2 * (0.01 + 0.2 * u(rng)) * w, v, 2 * (0.01 + 0.2 * u(rng)) * v};
  };
  for (int k = 0; k < 8; ++k) {
    model::Plant rigid;
    rigid.m = 1e-4 + u(rng);
    rigid.b = 1e-3 + u(rng);
    model::Plant one = rigid, two = rigid, both = rigid;
    one.modes = {section()};
    two.modes = {section()};
    both.modes = {one.modes[0], two.modes[0]};
    for (double w : {1.0, 150.0, 900.0, 3000.0}) {
      const std::complex<double> want =
          model::ContinuousResponse(one, w) * model::ContinuousResponse(two, w) / model::ContinuousResponse(rigid, w);
      EXPECT_LT(std::abs(model::ContinuousResponse(both, w) - want), 1e-12 * std::abs(want)) << k << " " << w;
    }
  }
}

// Each section has unit DC gain and high-frequency gain w^2/v^2: G (m s^2 + b s)
// -> 1 as w -> 0 and G m s^2 -> prod w_i^2/v_i^2 as w -> infinity (the
// neglected terms are O(w) and O(1/w): 1e-6 at the frequencies used).
TEST(Plant, SectionsHaveUnitDcGainAndTheirHighFrequencyGain) {
  const model::Plant p = model::PhantomTable1();
  ASSERT_FALSE(p.modes.empty());
  double hf = 1.0;
  for (const model::Mode& md : p.modes) hf *= md.omega * md.omega / (md.v * md.v);
  const double lo = 1e-6 * p.modes[0].v;
  const std::complex<double> s_lo(0.0, lo);
  EXPECT_LT(std::abs(model::ContinuousResponse(p, lo) * (p.m * s_lo * s_lo + p.b * s_lo) - 1.0), 1e-5);
  const double hi = 1e7 * p.modes.back().omega;
  const std::complex<double> s_hi(0.0, hi);
  EXPECT_LT(std::abs(model::ContinuousResponse(p, hi) * (p.m * s_hi * s_hi) / hf - 1.0), 1e-5);
  EXPECT_TRUE(std::isinf(std::abs(model::ContinuousResponse(p, 0.0))));
}

// Every parameter, set to 0, -1, NaN and infinity in turn, is refused with its
// own name (the fields enumerated here, not by the library).
TEST(Plant, EveryBadParameterIsRefusedByName) {
  const model::Plant good = model::PhantomTable1();
  ASSERT_GE(good.modes.size(), 1u);
  std::string why;
  ASSERT_TRUE(good.IsValid(&why)) << why;
  struct Field { const char* name; double* (*at)(model::Plant&); };
  const Field fields[] = {
      {"m", [](model::Plant& p) { return &p.m; }},
      {"b", [](model::Plant& p) { return &p.b; }},
      {"modes[0].omega", [](model::Plant& p) { return &p.modes[0].omega; }},
      {"modes[0].c", [](model::Plant& p) { return &p.modes[0].c; }},
      {"modes[0].v", [](model::Plant& p) { return &p.modes[0].v; }},
      {"modes[0].d", [](model::Plant& p) { return &p.modes[0].d; }},
  };
  for (const Field& f : fields) {
    for (double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
      model::Plant p = good;
      *f.at(p) = bad;
      why.clear();
      EXPECT_FALSE(p.IsValid(&why)) << f.name << " = " << bad;
      EXPECT_EQ(why.rfind(std::string(f.name) + " =", 0), 0u) << why;
      EXPECT_THROW(p.Validate(), InputError) << f.name;
    }
  }
  model::Plant p = good;
  p.delay_samples = -1;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("delay_samples"), std::string::npos) << why;
}

}  // namespace
}  // namespace zwidth
