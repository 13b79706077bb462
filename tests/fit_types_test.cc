// fit/fit_types.cc: the options' defaults and refusals by field, the enums'
// names both ways (moved from fit_test.cc and friction_fit_test.cc, tests unchanged).
#include <string>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "fit/friction_fit.h"

namespace zwidth::fit {
namespace {

TEST(Fit, DefaultOptionsAreValid) {
  std::string why;
  EXPECT_TRUE(FitOptions{}.IsValid(&why)) << why;
}

TEST(FrictionFitOptions, DefaultsAreValidAndBadFieldsAreNamed) {
  std::string why;
  EXPECT_TRUE(FrictionFitOptions{}.IsValid(&why)) << why;
  FrictionFitOptions o;
  o.cutoff_hz = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("cutoff_hz"), std::string::npos);
  o = {};
  o.min_speed_fraction = 1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("min_speed_fraction"), std::string::npos);
  o = {};
  o.iterations = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("iterations"), std::string::npos);
  o = {};
  o.detection_z = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("detection_z"), std::string::npos);
}

TEST(FrictionModel, NamesRoundTrip) {
  for (FrictionModel m : {FrictionModel::kNone, FrictionModel::kAuto, FrictionModel::kCoulomb}) {
    FrictionModel back = FrictionModel::kNone;
    EXPECT_TRUE(FrictionModelFromString(ToString(m), &back));
    EXPECT_EQ(back, m);
  }
  FrictionModel x;
  EXPECT_FALSE(FrictionModelFromString("viscous", &x));
}

}  // namespace
}  // namespace zwidth::fit
