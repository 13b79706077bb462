// The cut-off sweep of the haptic loop's low-pass velocity filter
// (stability/velocity_filter.h) and the stable area of a Z-width.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "model/plant.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

namespace zwidth::stability {

// ---- Cut-off sweep (Chawda, Celik and O'Malley's question, answered exactly):
// for each cut-off, the loop with a first-order low-pass velocity filter and the
// measure; the best cut-off maximises it.
enum class SweepMeasure {
  kKcrMax,  // K_CR^max of Summarize() [N m/rad]
  kArea,    // area of the stable (B, K) set for 0 <= B <= area_B_max [N m/rad x N m s/rad],
            // K_hi = +inf clipped at area_K_clip
};
std::string ToString(SweepMeasure m);
SweepMeasure SweepMeasureFromString(const std::string& s);  // "kcr-max" | "area"; InputError otherwise

struct CutoffSweepOptions {
  std::vector<double> cutoffs_hz;  // each in (0, 1/(2T)); not empty
  SweepMeasure measure = SweepMeasure::kKcrMax;
  double area_B_max = std::numeric_limits<double>::quiet_NaN();  // [N m s/rad], > 0 for kArea
  double area_K_clip = std::numeric_limits<double>::infinity();  // [N m/rad], > 0
  int area_B_points = 200;  // trapezoid points on [0, area_B_max], >= 2
  bool IsValid(double period_s, std::string* why) const;
};

struct CutoffSweepResult {
  std::vector<double> cutoffs_hz, measure;  // one per cut-off
  std::vector<DelaySummary> summaries;
  int best = -1;  // index of the largest finite measure; -1 = none finite
  // The same measure without a velocity filter (the hand kept): a filter is
  // worth having only where it beats this.
  double unfiltered = std::numeric_limits<double>::quiet_NaN();
  // The best is the first or the last cut-off: the optimum may lie outside
  // the swept range.
  bool best_at_edge = false;
};

// The hand in `loop` is kept; its filter is replaced by each low-pass.
CutoffSweepResult SweepCutoff(const model::Plant& plant, double period_s, int delay_samples,
                              const LoopOptions& loop, const CutoffSweepOptions& options);

// Area of the stable set of z for 0 <= B <= B_max (trapezoid on `points` values of B).
double StableArea(const ZWidth& z, double B_max, double K_clip, int points);

}  // namespace zwidth::stability
