#include "ident/encoder_step.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace zwidth::ident {

double EncoderStep(std::span<const double> y) {
  const size_t n = y.size();
  if (n < 2) return 0.0;
  double span = 0.0;
  for (double v : y) {
    if (!std::isfinite(v)) return 0.0;
    span = std::max(span, std::abs(v - y[0]));
  }
  if (!(span > 0.0)) return 0.0;
  // Steps far below double's resolution of the span are rounding, not counts.
  const double floor = 64.0 * std::numeric_limits<double>::epsilon() * (span + std::abs(y[0]));
  double q = std::numeric_limits<double>::infinity();
  int moves = 0;
  for (size_t i = 1; i < n; ++i) {
    const double d = std::abs(y[i] - y[i - 1]);
    if (d > floor) {
      q = std::min(q, d);
      ++moves;
    }
  }
  if (moves < kMinMoves || !(span >= kMinCounts * q)) return 0.0;
  // The counts k_i from the steps between samples (each a few counts, so
  // rounding d / q is safe where q's error would grow with k in (y - y_0) / q),
  // the least-squares step q = sum k (y - y_0) / sum k^2, and every sample but
  // 1 in 1000 within kGridTolerance steps of y_0 + k q.
  std::vector<double> k(n, 0.0);
  double kk = 0.0, ky = 0.0;
  for (size_t i = 1; i < n; ++i) {
    k[i] = k[i - 1] + std::round((y[i] - y[i - 1]) / q);
    kk += k[i] * k[i];
    ky += k[i] * (y[i] - y[0]);
  }
  if (!(kk > 0.0)) return 0.0;
  const double step = ky / kk;
  const size_t allowed = n / 1000;
  size_t off = 0;
  for (size_t i = 0; i < n; ++i) {
    if (std::abs(y[i] - y[0] - k[i] * step) > kGridTolerance * step && ++off > allowed) return 0.0;
  }
  return step;
}

}  // namespace zwidth::ident
