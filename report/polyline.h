// Thinning of drawn polylines to what a figure of a given size can show: the
// rows of a table whose points lie within a fraction of a pixel of the line
// through their neighbours are dropped before gnuplot reads them. Internal to
// report/ (not installed).
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace zwidth::report {

// Where a value lands on a drawn axis: pixel = px_per_unit * v, or
// px_per_unit * log10(v) on a logarithmic axis.
struct PixelAxis {
  double px_per_unit = 1.0;  // pixels per data unit (per decade when log), > 0
  bool log = false;          // logarithmic axis: values <= 0 are not drawn
  // The pixel coordinate of v; NaN when v is not drawn (not finite, <= 0 on a log axis).
  double ToPixel(double v) const;
};

// The axis on which the drawn part of `values` (each clamped to [lo, hi], the
// axis range when it is fixed) spans `pixels`. When the figure draws that
// range across at most `pixels` (the canvas size is such a bound; autoscaling
// only widens the range), a distance in pixels on this axis bounds the
// drawn one. A single value or none gives 1 px per unit.
PixelAxis AxisSpanning(const std::vector<double>& values, double pixels, bool log,
                       double lo = -std::numeric_limits<double>::infinity(),
                       double hi = std::numeric_limits<double>::infinity());

// One polyline y(x) of a table drawn on the axis y_axis.
struct DrawnSeries {
  const std::vector<double>* y = nullptr;  // one value per row (same length as x)
  PixelAxis y_axis;
};

// The rows of the table (x[i], y_j[i]) to keep, increasing, when every series
// y_j is drawn as a polyline against x: each dropped row's point lies within
// tol_px (Euclidean, in pixels) of the segment joining the kept rows around it,
// for every series drawn at that row (Ramer-Douglas-Peucker, per run). A row
// where the set of drawn series changes (a value NaN, infinite or <= 0 on a log
// axis: the line breaks there) is kept with its neighbour, so breaks stay where
// they were. The first and last rows are always kept. tol_px >= 0.
std::vector<size_t> ThinPolylines(const std::vector<double>& x, const PixelAxis& x_axis,
                                  const std::vector<DrawnSeries>& ys, double tol_px);

// The distance from (px, py) to the segment (ax, ay)-(bx, by) [pixels].
double DistanceToSegment(double px, double py, double ax, double ay, double bx, double by);

}  // namespace zwidth::report
