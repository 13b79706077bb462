// stability/cutoff_sweep.h: the sweep of the velocity filter's cut-off against
// ZWidth summarised at each cut-off (moved from haptic_loop_test.cc, tests unchanged).
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/plant.h"
#include "stability/cutoff_sweep.h"
#include "stability/loop_options.h"
#include "stability/velocity_filter.h"
#include "stability/zwidth.h"
#include "tests/test_util.h"

namespace zwidth::stability {
namespace {

TEST(CutoffSweep, BestCutoffHasTheLargestMeasure) {
  std::mt19937_64 rng(4);
  const model::Plant p = test::RandomPlausibleDevice(rng, 1);
  CutoffSweepOptions o;
  for (int i = 0; i < 8; ++i) o.cutoffs_hz.push_back(5.0 * std::pow(40.0, i / 7.0));
  const CutoffSweepResult r = SweepCutoff(p, 1e-3, 2, LoopOptions{}, o);
  ASSERT_GE(r.best, 0);
  for (int i = 0; i < 8; ++i) {
    LoopOptions l;
    SetLowPassFilter(o.cutoffs_hz[i], 1e-3, &l);
    EXPECT_EQ(r.measure[i], ZWidth(p, 1e-3, 2, l).Summarize().K_cr_max);
    EXPECT_LE(r.measure[i], r.measure[r.best]);
  }
  // The loop without a filter, beside the sweep, and whether the best is at an end.
  EXPECT_EQ(r.unfiltered, ZWidth(p, 1e-3, 2).Summarize().K_cr_max);
  EXPECT_EQ(r.best_at_edge, r.best == 0 || r.best == 7);
}

}  // namespace
}  // namespace zwidth::stability
