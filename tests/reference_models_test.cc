#include "io/reference_models.h"

#include <gtest/gtest.h>

namespace zwidth::io {
namespace {

// Table I of Gil et al., as printed in the paper (not read from the embedded file).
TEST(ReferenceModels, Table1IsThePapersTableI) {
  const ModelFile t = Table1Model();
  EXPECT_DOUBLE_EQ(t.plant.m, 1.168e-3);
  EXPECT_DOUBLE_EQ(t.plant.b, 0.00584);
  ASSERT_EQ(t.plant.modes.size(), 2u);
  EXPECT_DOUBLE_EQ(t.plant.modes[0].omega, 479.166);
  EXPECT_DOUBLE_EQ(t.plant.modes[1].v, 546.626);
  EXPECT_EQ(t.plant.delay_samples, 0);
}

// Table II: the delays 2, 4, 8 ms; the two misprinted rows carry a note and are left out.
TEST(ReferenceModels, Table2KeepsTheUnflaggedRows) {
  const auto pts = Table2Points();
  ASSERT_FALSE(pts.empty());
  EXPECT_EQ(pts.front().delay_samples, 2);
  EXPECT_DOUBLE_EQ(pts.front().B, 0.0);
  EXPECT_DOUBLE_EQ(pts.front().K_cr, 7.21);
  EXPECT_DOUBLE_EQ(pts.front().f_cr_hz, 13.61);
  for (const auto& p : pts) EXPECT_TRUE(p.delay_samples == 2 || p.delay_samples == 4 || p.delay_samples == 8);
}

}  // namespace
}  // namespace zwidth::io
