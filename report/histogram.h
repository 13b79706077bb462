// The bins of the fleet report's distributions (report/fleet_report.h): a
// range set by robust statistics, so that one wild unit (a wrong sign, a
// factor of 1000) does not stretch the axis and squash the population into
// one bin; the values beyond the range are counted, and the report shows
// those counts as labels beyond the edges. Prints nothing.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace zwidth::report {

struct HistogramOptions {
  int bins = 30;              // bins across the range, in [1, 1000]
  // The range is median +- mad_multiple * s, s = the population's MAD sigma
  // (1.4826 MAD, analysis/population.h), clipped to the values' min and max.
  // 6: a normal population of 10^6 units has ~2 beyond either edge. > 0, finite.
  double mad_multiple = 6.0;
  // When s = 0 (more than half the values equal), the range is the
  // [tail, 1 - tail] quantiles of the values instead; in (0, 0.5).
  double tail = 0.01;
  bool IsValid(std::string* why) const;
};

struct HistogramBins {
  double lo = 0.0, hi = 0.0;  // the range the bins cover, lo < hi (5 % padding included)
  std::vector<size_t> counts;  // bins of width (hi - lo) / bins; a value at hi is in the last
  size_t below = 0, above = 0;  // values < lo and > hi: shown beyond the edges, with the extremes
  double min = 0.0, max = 0.0;  // of the finite values
  size_t values = 0;            // finite values binned or counted beyond (nan and inf are left out)
};

// Bins the finite `values` (at least one) over the robust range around
// `median` with spread `mad_sigma` (the population's, >= 0), widened to take
// in each of `marks` (specs' bounds, the design's value) that lies within
// the range's own width of it; a mark farther out is not in the range (the
// caller notes it). InputError for options that are not IsValid, or no
// finite value.
HistogramBins RobustHistogram(const std::vector<double>& values, double median, double mad_sigma,
                              const std::vector<double>& marks, const HistogramOptions& options = {});

}  // namespace zwidth::report
