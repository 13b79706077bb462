// stability/loop_options.h: the loop's options, valid by default and refused
// with the field's name (moved from haptic_loop_test.cc, tests unchanged).
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/error.h"
#include "stability/loop_options.h"
#include "stability/passivity.h"
#include "stability/velocity_filter.h"

namespace zwidth::stability {
namespace {

TEST(HapticLoop, DefaultOptionsAreValidAndBadOnesNameTheirField) {
  std::string why;
  EXPECT_TRUE(LoopOptions{}.IsValid(&why));
  EXPECT_TRUE(PassivityOptions{}.IsValid(&why));
  LoopOptions l;
  l.filter_b = {0.5};
  l.filter_a = {1.0, -1.2};  // pole at 1.2
  EXPECT_FALSE(l.IsValid(&why));
  EXPECT_NE(why.find("filter_a"), std::string::npos);
  l.filter_a = {2.0, -0.5};
  EXPECT_FALSE(l.IsValid(&why));
  EXPECT_NE(why.find("a0"), std::string::npos);
  l = {};
  l.hand.K = -1.0;
  EXPECT_FALSE(l.IsValid(&why));
  EXPECT_NE(why.find("hand.K"), std::string::npos);
  l = {};
  EXPECT_THROW(SetLowPassFilter(600.0, 1e-3, &l), InputError);
}

}  // namespace
}  // namespace zwidth::stability
