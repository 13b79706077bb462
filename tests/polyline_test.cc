// report::ThinPolylines against a brute force written here: every dropped row
// lies within the tolerance of the kept polyline (the distance to each of its
// segments computed directly), on seeded random curves; breaks (NaN, <= 0 on a
// log axis) stay where they were.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "report/polyline.h"

namespace zwidth::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Pixel coordinate, NaN when not drawn (written apart from PixelAxis::ToPixel).
double Px(double v, double scale, bool log) {
  if (!std::isfinite(v) || (log && v <= 0)) return kNaN;
  return scale * (log ? std::log10(v) : v);
}

// Distance from p to segment ab, by cases (written apart from the library's
// clamped projection): beyond an end, the distance to that end; else the
// height of the triangle (a, b, p) over ab.
double BruteDistance(double px, double py, double ax, double ay, double bx, double by) {
  const double ux = bx - ax, uy = by - ay;
  if ((px - ax) * ux + (py - ay) * uy <= 0) return std::hypot(px - ax, py - ay);
  if ((px - bx) * -ux + (py - by) * -uy <= 0) return std::hypot(px - bx, py - by);
  return std::abs(ux * (py - ay) - uy * (px - ax)) / std::hypot(ux, uy);
}

struct Case {
  std::vector<double> x;
  std::vector<std::vector<double>> ys;
  PixelAxis xa;
  std::vector<PixelAxis> ya;
};

// Every row i not kept: for every series drawn at i, the kept rows around it
// (the nearest kept below and above) are drawn there too, and the point lies
// within tol of their segment.
void ExpectWithinTolerance(const Case& c, const std::vector<size_t>& kept, double tol) {
  const size_t n = c.x.size();
  ASSERT_FALSE(kept.empty());
  EXPECT_EQ(kept.front(), 0u);
  EXPECT_EQ(kept.back(), n - 1);
  std::vector<char> is_kept(n, 0);
  for (size_t i = 0; i < kept.size(); ++i) {
    if (i) ASSERT_LT(kept[i - 1], kept[i]);
    is_kept[kept[i]] = 1;
  }
  size_t below = 0;
  for (size_t i = 0; i < n; ++i) {
    if (is_kept[i]) {
      below = i;
      continue;
    }
    size_t above = i + 1;
    while (!is_kept[above]) ++above;
    for (size_t j = 0; j < c.ys.size(); ++j) {
      const double xi = Px(c.x[i], c.xa.px_per_unit, c.xa.log);
      const double yi = Px(c.ys[j][i], c.ya[j].px_per_unit, c.ya[j].log);
      const double xa = Px(c.x[below], c.xa.px_per_unit, c.xa.log), xb = Px(c.x[above], c.xa.px_per_unit, c.xa.log);
      const double ya = Px(c.ys[j][below], c.ya[j].px_per_unit, c.ya[j].log);
      const double yb = Px(c.ys[j][above], c.ya[j].px_per_unit, c.ya[j].log);
      const bool drawn_i = !std::isnan(xi) && !std::isnan(yi);
      const bool drawn_a = !std::isnan(xa) && !std::isnan(ya), drawn_b = !std::isnan(xb) && !std::isnan(yb);
      // A dropped row is drawn exactly when its kept neighbours are (breaks kept).
      ASSERT_EQ(drawn_i, drawn_a) << "row " << i << " series " << j;
      ASSERT_EQ(drawn_i, drawn_b) << "row " << i << " series " << j;
      if (!drawn_i) continue;
      EXPECT_LE(BruteDistance(xi, yi, xa, ya, xb, yb), tol + 1e-9) << "row " << i << " series " << j;
    }
  }
}

// A random smooth curve plus noise of random size, with a few NaN rows and a
// few non-positive values (breaks on the log axes).
Case RandomCase(std::mt19937& rng, size_t n, int num_series) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Case c;
  c.xa = {900.0 / 3.0, true};  // x from 10^0 to 10^3 over 900 px, logarithmic
  double x = 1.0;
  for (size_t i = 0; i < n; ++i) {
    c.x.push_back(x);
    x *= std::pow(1000.0, 1.0 / static_cast<double>(n - 1)) * (0.999 + 0.002 * u(rng));
  }
  for (int j = 0; j < num_series; ++j) {
    const bool log = j % 2 == 0;
    const double noise = std::pow(10.0, -4 + 4 * u(rng));
    const double f1 = 1 + 20 * u(rng), f2 = 1 + 5 * u(rng);
    std::vector<double> y(n);
    for (size_t i = 0; i < n; ++i) {
      const double t = static_cast<double>(i) / static_cast<double>(n);
      const double s = std::sin(f1 * t) + 0.3 * std::cos(f2 * 7 * t) + noise * (u(rng) - 0.5);
      y[i] = log ? std::pow(10.0, 2 * s) : 50 * s;
      if (u(rng) < 0.01) y[i] = kNaN;
      if (log && u(rng) < 0.005) y[i] = 0.0;
    }
    c.ys.push_back(y);
    c.ya.push_back(AxisSpanning(y, 640, log));
  }
  return c;
}

std::vector<DrawnSeries> Series(const Case& c) {
  std::vector<DrawnSeries> s;
  for (size_t j = 0; j < c.ys.size(); ++j) s.push_back({&c.ys[j], c.ya[j]});
  return s;
}

class ThinPolylinesRandom : public ::testing::TestWithParam<double> {};

TEST_P(ThinPolylinesRandom, EveryDroppedRowLiesWithinTheToleranceOfTheKeptPolyline) {
  const double tol = GetParam();
  std::mt19937 rng(20261127);
  size_t total = 0, kept_total = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Case c = RandomCase(rng, 200 + 50 * static_cast<size_t>(trial), 1 + trial % 3);
    const std::vector<size_t> kept = ThinPolylines(c.x, c.xa, Series(c), tol);
    ExpectWithinTolerance(c, kept, tol);
    total += c.x.size();
    kept_total += kept.size();
  }
  // From a fifth of a pixel on, something is dropped (the curves are smooth
  // between the noise).
  if (tol >= 0.2) EXPECT_LT(kept_total, total);
}

INSTANTIATE_TEST_SUITE_P(Tolerances, ThinPolylinesRandom, ::testing::Values(0.0, 0.05, 0.2, 1.0, 5.0),
                         [](const auto& info) { return "tol_" + std::to_string(static_cast<int>(info.param * 100)) + "_centipx"; });

TEST(ThinPolylines, AStraightLineKeepsItsEndsAndAKinkKeepsTheCorner) {
  std::vector<double> x, y;
  for (int i = 0; i <= 100; ++i) {
    x.push_back(i);
    y.push_back(i <= 60 ? 2.0 * i : 120.0 - 3.0 * (i - 60));
  }
  const PixelAxis ax{1.0, false};
  EXPECT_EQ(ThinPolylines(x, ax, {{&y, ax}}, 0.1), (std::vector<size_t>{0, 60, 100}));
  std::vector<double> line(x.size());
  for (size_t i = 0; i < x.size(); ++i) line[i] = 0.5 * x[i] - 3;
  EXPECT_EQ(ThinPolylines(x, ax, {{&line, ax}}, 1e-9), (std::vector<size_t>{0, 100}));
}

TEST(ThinPolylines, ABreakKeepsTheRowsAroundItAndEmptyInputGivesNothing) {
  const std::vector<double> x = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const std::vector<double> y = {0, 1, 2, 3, kNaN, kNaN, 6, 7, 8};
  const PixelAxis ax{1.0, false};
  EXPECT_EQ(ThinPolylines(x, ax, {{&y, ax}}, 0.1), (std::vector<size_t>{0, 3, 4, 5, 6, 8}));
  const std::vector<double> none;
  EXPECT_TRUE(ThinPolylines(none, ax, {{&none, ax}}, 0.1).empty());
}

TEST(ThinPolylines, ASpikeNarrowerThanAPixelIsKeptWhenItRisesAboveTheTolerance) {
  std::vector<double> x, y;
  for (int i = 0; i < 1000; ++i) {
    x.push_back(i * 1e-3);  // 1000 rows across 1 px
    y.push_back(i == 500 ? 1.0 : 0.0);
  }
  const std::vector<size_t> kept = ThinPolylines(x, {1.0, false}, {{&y, {1.0, false}}}, 0.25);
  EXPECT_NE(std::find(kept.begin(), kept.end(), 500u), kept.end());
}

TEST(AxisSpanning, MapsTheClampedDrawnRangeOntoThePixels) {
  const std::vector<double> v = {kNaN, -5, 1, 3, 100, std::numeric_limits<double>::infinity()};
  EXPECT_DOUBLE_EQ(AxisSpanning(v, 600, false).px_per_unit, 600.0 / 105.0);
  EXPECT_DOUBLE_EQ(AxisSpanning(v, 600, false, 0.0, 10.0).px_per_unit, 60.0);
  EXPECT_DOUBLE_EQ(AxisSpanning(v, 600, true).px_per_unit, 300.0);  // 1 to 100: two decades
  EXPECT_DOUBLE_EQ(AxisSpanning(std::vector<double>{7.0}, 600, false).px_per_unit, 1.0);
  const PixelAxis log1{1.0, true}, log2{2.0, true};
  EXPECT_TRUE(std::isnan(log1.ToPixel(0.0)));
  EXPECT_DOUBLE_EQ(log2.ToPixel(1000.0), 6.0);
}

}  // namespace
}  // namespace zwidth::report
