// The Schur-Cohn test of stability/schur_cohn.h on polynomials whose roots are known.
#include <gtest/gtest.h>

#include "stability/schur_cohn.h"

namespace zwidth::stability {
namespace {

TEST(SchurCohn, KnownPolynomials) {
  EXPECT_TRUE(AllRootsInsideUnitCircle({0.25, -1.0, 1.0}));   // (z-0.5)^2
  EXPECT_FALSE(AllRootsInsideUnitCircle({-1.0, 0.0, 1.0}));   // roots on the circle
  EXPECT_FALSE(AllRootsInsideUnitCircle({-1.1, 1.0}));        // z = 1.1
  EXPECT_TRUE(AllRootsInsideUnitCircle({0.5}));
}

}  // namespace
}  // namespace zwidth::stability
