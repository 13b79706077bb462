#include "report/polyline.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <utility>

namespace zwidth::report {

double PixelAxis::ToPixel(double v) const {
  if (!std::isfinite(v) || (log && !(v > 0))) return std::numeric_limits<double>::quiet_NaN();
  return px_per_unit * (log ? std::log10(v) : v);
}

PixelAxis AxisSpanning(const std::vector<double>& values, double pixels, bool log, double lo, double hi) {
  PixelAxis a;
  a.log = log;
  double mn = std::numeric_limits<double>::infinity(), mx = -mn;
  for (double v : values) {
    if (!std::isfinite(v) || (log && !(v > 0))) continue;
    v = std::clamp(v, lo, hi);
    if (log && !(v > 0)) continue;
    const double u = log ? std::log10(v) : v;
    mn = std::min(mn, u);
    mx = std::max(mx, u);
  }
  if (mx > mn) a.px_per_unit = pixels / (mx - mn);
  return a;
}

namespace {

// The squared distance from (px, py) to the segment (ax, ay)-(bx, by).
double SquaredDistanceToSegment(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const double ex = px - (ax + t * dx), ey = py - (ay + t * dy);
  return ex * ex + ey * ey;
}

}  // namespace

double DistanceToSegment(double px, double py, double ax, double ay, double bx, double by) {
  return std::sqrt(SquaredDistanceToSegment(px, py, ax, ay, bx, by));
}

std::vector<size_t> ThinPolylines(const std::vector<double>& x, const PixelAxis& x_axis,
                                  const std::vector<DrawnSeries>& ys, double tol_px) {
  const size_t n = x.size(), m = ys.size();
  assert(m <= 32 && tol_px >= 0);
  // Pixel coordinates (NaN: not drawn) and the set of series drawn per row.
  std::vector<double> px(n);
  std::vector<double> py(n * m);
  std::vector<uint32_t> mask(n, 0);
  for (size_t i = 0; i < n; ++i) {
    px[i] = x_axis.ToPixel(x[i]);
    for (size_t j = 0; j < m; ++j) {
      assert(ys[j].y->size() == n);
      py[i * m + j] = ys[j].y_axis.ToPixel((*ys[j].y)[i]);
      if (!std::isnan(px[i]) && !std::isnan(py[i * m + j])) mask[i] |= uint32_t{1} << j;
    }
  }
  std::vector<char> keep(n, 0);
  std::vector<std::pair<size_t, size_t>> stack;
  for (size_t a = 0; a < n;) {
    size_t b = a;
    while (b + 1 < n && mask[b + 1] == mask[a]) ++b;
    keep[a] = keep[b] = 1;
    if (mask[a] != 0) stack.emplace_back(a, b);
    // Ramer-Douglas-Peucker on rows a..b: the farthest row from the chord is
    // kept while it is farther than tol_px, and each half is done again.
    while (!stack.empty()) {
      const auto [s, e] = stack.back();
      stack.pop_back();
      double worst = tol_px * tol_px;  // squared distances from here on
      size_t at = s;
      for (size_t i = s + 1; i < e; ++i) {
        for (size_t j = 0; j < m; ++j) {
          if (!(mask[a] >> j & 1)) continue;
          const double d = SquaredDistanceToSegment(px[i], py[i * m + j], px[s], py[s * m + j], px[e], py[e * m + j]);
          if (d > worst) {
            worst = d;
            at = i;
          }
        }
      }
      if (at != s) {
        keep[at] = 1;
        stack.emplace_back(s, at);
        stack.emplace_back(at, e);
      }
    }
    a = b + 1;
  }
  std::vector<size_t> kept;
  for (size_t i = 0; i < n; ++i) {
    if (keep[i]) kept.push_back(i);
  }
  return kept;
}

}  // namespace zwidth::report
