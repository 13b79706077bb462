#include "stability/velocity_filter.h"

#include <cmath>
#include <cstdio>
#include <numbers>

#include "model/error.h"

namespace zwidth::stability {

void SetLowPassFilter(double cutoff_hz, double period_s, LoopOptions* loop) {
  if (!(std::isfinite(cutoff_hz) && cutoff_hz > 0.0 && cutoff_hz < 0.5 / period_s)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "SetLowPassFilter::cutoff_hz = %g: must be > 0 and below the Nyquist frequency %g Hz",
                  cutoff_hz, 0.5 / period_s);
    throw InputError(buf);
  }
  const double a = std::exp(-2.0 * std::numbers::pi * cutoff_hz * period_s);
  loop->filter_b = {1.0 - a};
  loop->filter_a = {1.0, -a};
}

}  // namespace zwidth::stability
