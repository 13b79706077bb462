// ident::EncoderStep against logs made here with a known step: an encoder's
// counts (a random walk and a swept sine, rounded to whole counts, on an
// arbitrary offset), the same printed to 6 significant digits as a text log
// would, and positions that are not quantised.
#include "ident/encoder_step.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace {

using zwidth::ident::EncoderStep;

// n samples of a device's position: a slow sine of a few hundred steps plus a
// random walk, in rad.
std::vector<double> Motion(size_t n, double q, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<double> y(n);
  double walk = 0.0;
  for (size_t i = 0; i < n; ++i) {
    walk += 0.7 * q * g(rng);
    y[i] = 300.0 * q * std::sin(2.0 * std::numbers::pi * 1.3 * static_cast<double>(i) / 1000.0) + walk;
  }
  return y;
}

std::vector<double> Quantised(std::vector<double> y, double q, double offset) {
  for (double& v : y) v = offset + q * std::round(v / q);
  return y;
}

TEST(EncoderStep, CountsOnAnOffsetGiveTheStep) {
  for (const double counts : {4000.0, 40960.0, 1e6}) {
    const double q = 2.0 * std::numbers::pi / counts;
    for (unsigned seed : {1u, 2u, 3u}) {
      const std::vector<double> y = Quantised(Motion(20000, q, seed), q, 0.123456789 + seed);
      EXPECT_NEAR(EncoderStep(y), q, 1e-9 * q) << counts << " counts, seed " << seed;
    }
  }
}

TEST(EncoderStep, ATextLogsSixDigitsStillGiveTheStep) {
  const double q = 2.0 * std::numbers::pi / 40960.0;
  std::vector<double> y = Quantised(Motion(20000, q, 4), q, 1.0);  // ~1 rad: 6 digits are 5e-7 rad, q / 300
  for (double& v : y) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    v = std::strtod(b, nullptr);
  }
  EXPECT_NEAR(EncoderStep(y), q, 1e-4 * q);
}

TEST(EncoderStep, AContinuousOrNoisyPositionHasNone) {
  const double q = 2.0 * std::numbers::pi / 4000.0;
  EXPECT_EQ(EncoderStep(Motion(20000, q, 5)), 0.0);  // not rounded
  std::vector<double> y = Quantised(Motion(20000, q, 6), q, 0.0);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  for (double& v : y) v += 0.05 * q * g(rng);  // sensor noise of 1/20 count on the counts
  EXPECT_EQ(EncoderStep(y), 0.0);
}

TEST(EncoderStep, AStillOrShortLogCannotTell) {
  EXPECT_EQ(EncoderStep(std::vector<double>(5000, 0.25)), 0.0);
  EXPECT_EQ(EncoderStep(std::vector<double>{}), 0.0);
  // Four moves of one count (at samples 1000-4000): too few to tell a grid from chance.
  std::vector<double> y(5000, 0.0);
  for (size_t i = 1000; i < 6000 && i < y.size(); i += 1000) for (size_t j = i; j < y.size(); ++j) y[j] += 1e-3;
  EXPECT_EQ(EncoderStep(y), 0.0);
  std::vector<double> bad = Quantised(Motion(5000, 1e-3, 8), 1e-3, 0.0);
  bad[100] = std::nan("");
  EXPECT_EQ(EncoderStep(bad), 0.0);
}

}  // namespace
