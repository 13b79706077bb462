#include "report/histogram.h"

#include <algorithm>
#include <cmath>

#include "model/error.h"

namespace zwidth::report {
namespace {

// The q-quantile of sorted values, linear between order statistics (Hyndman
// and Fan's type 7, R's and NumPy's default).
double SortedQuantile(const std::vector<double>& sorted, double q) {
  const double h = q * static_cast<double>(sorted.size() - 1);
  const size_t k = static_cast<size_t>(std::floor(h));
  if (k + 1 >= sorted.size()) return sorted.back();
  return sorted[k] + (h - static_cast<double>(k)) * (sorted[k + 1] - sorted[k]);
}

}  // namespace

bool HistogramOptions::IsValid(std::string* why) const {
  if (bins < 1 || bins > 1000) {
    *why = "HistogramOptions::bins = " + std::to_string(bins) + ": must be in [1, 1000]";
    return false;
  }
  if (!(mad_multiple > 0) || !std::isfinite(mad_multiple)) {
    *why = "HistogramOptions::mad_multiple = " + std::to_string(mad_multiple) + ": must be finite, > 0";
    return false;
  }
  if (!(tail > 0 && tail < 0.5)) {
    *why = "HistogramOptions::tail = " + std::to_string(tail) + ": must be in (0, 0.5)";
    return false;
  }
  return true;
}

HistogramBins RobustHistogram(const std::vector<double>& values, double median, double mad_sigma,
                              const std::vector<double>& marks, const HistogramOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  std::vector<double> v;
  for (double x : values) if (std::isfinite(x)) v.push_back(x);
  if (v.empty()) throw InputError("RobustHistogram: no finite value to bin");
  std::sort(v.begin(), v.end());
  HistogramBins out;
  out.values = v.size();
  out.min = v.front(), out.max = v.back();
  // The window: median +- k s, clipped to the values; with s = 0 (or not
  // given) the [tail, 1 - tail] quantiles; when those are equal too, all the
  // values but the outermost ones are one number: a unit-wide window around it.
  double lo, hi;
  if (mad_sigma > 0 && std::isfinite(mad_sigma) && std::isfinite(median)) {
    lo = std::max(out.min, median - options.mad_multiple * mad_sigma);
    hi = std::min(out.max, median + options.mad_multiple * mad_sigma);
  } else {
    lo = SortedQuantile(v, options.tail);
    hi = SortedQuantile(v, 1.0 - options.tail);
  }
  if (!(hi > lo)) {
    const double c = std::isfinite(median) ? median : lo;
    const double w = std::max(0.5 * std::abs(c), 0.5);
    lo = std::max(out.min, c - w), hi = std::min(out.max, c + w);
    if (!(hi > lo)) lo = c - w, hi = c + w;  // every value equal
  }
  // Marks near the window (within its width) are taken in: a spec's bound
  // just outside the population is what the reader looks for.
  const double width = hi - lo;
  double mlo = lo, mhi = hi;
  for (double m : marks) {
    if (!std::isfinite(m) || m < lo - width || m > hi + width) continue;
    mlo = std::min(mlo, m), mhi = std::max(mhi, m);
  }
  const double pad = 0.05 * (mhi - mlo);
  out.lo = mlo - pad, out.hi = mhi + pad;
  out.counts.assign(static_cast<size_t>(options.bins), 0);
  const double bin = (out.hi - out.lo) / options.bins;
  for (double x : v) {
    if (x < out.lo) {
      ++out.below;
    } else if (x > out.hi) {
      ++out.above;
    } else {
      const size_t i = std::min(static_cast<size_t>((x - out.lo) / bin), out.counts.size() - 1);
      ++out.counts[i];
    }
  }
  return out;
}

}  // namespace zwidth::report
