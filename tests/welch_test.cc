#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "ident/fft.h"
#include "ident/welch.h"
#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"

namespace zwidth::ident {
namespace {

using cd = std::complex<double>;

std::vector<double> Noise(size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> d(0, 1);
  std::vector<double> v(n);
  for (double& x : v) x = d(rng);
  return v;
}

// y = filter([b0 b1 b2], [1 a1 a2], u), a known stable discrete filter.
std::vector<double> Filter(const std::vector<double>& u) {
  const double b0 = 0.2, b1 = 0.3, b2 = -0.1, a1 = -0.9, a2 = 0.5;
  std::vector<double> y(u.size());
  for (size_t k = 0; k < u.size(); ++k) {
    y[k] = b0 * u[k] + (k > 0 ? b1 * u[k - 1] - a1 * y[k - 1] : 0) + (k > 1 ? b2 * u[k - 2] - a2 * y[k - 2] : 0);
  }
  return y;
}
cd FilterResponse(double theta) {
  const cd z1 = std::polar(1.0, -theta);
  return (0.2 + 0.3 * z1 - 0.1 * z1 * z1) / (1.0 - 0.9 * z1 + 0.5 * z1 * z1);
}

TEST(Welch, WhiteNoiseThroughKnownFilterGivesItsResponseWithinTheStatedStd) {
  const auto u = Noise(200000, 1);
  auto y = Filter(u);
  const auto e = Noise(y.size(), 2);
  for (size_t k = 0; k < y.size(); ++k) y[k] += 0.2 * e[k];
  WelchOptions o;
  o.window_length = 1024;
  o.fmin_hz = 1;
  o.fmax_hz = 499;
  const FrequencyResponse r = EstimateFrequencyResponse(u, y, 1000, o);
  int within2 = 0;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    const cd truth = FilterResponse(2 * std::numbers::pi * r.f_hz[k] / 1000);
    if (std::abs(r.H[k] - truth) < 2.0 * r.H_std[k] * std::sqrt(2.0)) ++within2;
  }
  // |error|/sd follows a Rayleigh law: about 98% within 2 sqrt(2) sd.
  EXPECT_GT(within2, 0.93 * r.f_hz.size());
  EXPECT_LT(within2, r.f_hz.size() + 1);
}

TEST(Welch, WelchOfWhiteNoiseIsFlat) {
  const auto u = Noise(400000, 3);
  WelchOptions o;
  o.window_length = 512;
  o.fmin_hz = 5;
  o.fmax_hz = 495;
  const FrequencyResponse r = EstimateFrequencyResponse(u, u, 1000, o);
  double mean = 0;
  for (double s : r.S_uu) mean += s;
  mean /= r.S_uu.size();
  EXPECT_NEAR(mean, 2.0 / 1000.0, 0.02 * 2.0 / 1000.0);  // one-sided density of unit variance
  for (double s : r.S_uu) EXPECT_NEAR(s / mean, 1.0, 0.25);
}

TEST(Welch, NoiseFreeH1EqualsH2EqualsTheTruth) {
  // A random block repeated: after the filter's transient every segment is
  // exactly periodic, so the estimate has no leakage and equals the truth.
  const auto block = Noise(4096, 4);
  std::vector<double> u;
  for (int r = 0; r < 12; ++r) u.insert(u.end(), block.begin(), block.end());
  auto y = Filter(u);
  u.erase(u.begin(), u.begin() + 4096);
  y.erase(y.begin(), y.begin() + 4096);
  WelchOptions o;
  o.window_length = 4096;
  o.detrend = Detrend::kNone;
  o.window = Window::kRect;
  o.overlap = 0.0;
  const FrequencyResponse h1 = EstimateFrequencyResponse(u, y, 1000, o);
  o.estimator = Estimator::kH2;
  const FrequencyResponse h2 = EstimateFrequencyResponse(u, y, 1000, o);
  for (size_t k = 0; k < h1.f_hz.size(); ++k) {
    EXPECT_LT(std::abs(h1.H[k] - h2.H[k]) / std::abs(h1.H[k]), 1e-9);
    EXPECT_NEAR(h1.coherence[k], 1.0, 1e-9);
    const std::complex<double> truth = FilterResponse(2 * std::numbers::pi * h1.f_hz[k] / 1000);
    EXPECT_LT(std::abs(h1.H[k] - truth) / std::abs(truth), 1e-9);
  }
}

TEST(Welch, EqualsAPlainDftImplementation) {
  const auto u = Noise(3000, 5);
  const auto y = Filter(u);
  WelchOptions o;
  o.window_length = 256;
  o.overlap = 0.3;
  o.fmin_hz = 0;
  o.fmax_hz = 500;
  const double fs = 1000;
  const FrequencyResponse r = EstimateFrequencyResponse(u, y, fs, o);
  const int n = 256, step = n - static_cast<int>(std::floor(0.3 * n));
  const std::vector<double> w = MakeWindow(Window::kHann, n);
  std::vector<double> suu(n / 2 + 1, 0), syy(n / 2 + 1, 0);
  std::vector<cd> suy(n / 2 + 1, 0);
  int segs = 0;
  for (int s = 0; s + n <= 3000; s += step, ++segs) {
    std::vector<double> a(u.begin() + s, u.begin() + s + n), b(y.begin() + s, y.begin() + s + n);
    for (auto* v : {&a, &b}) {  // linear detrend by normal equations
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      for (int i = 0; i < n; ++i) { sx += i; sy += (*v)[i]; sxx += 1.0 * i * i; sxy += i * (*v)[i]; }
      const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), icpt = (sy - slope * sx) / n;
      for (int i = 0; i < n; ++i) (*v)[i] = ((*v)[i] - icpt - slope * i) * w[i];
    }
    for (int k = 0; k <= n / 2; ++k) {
      cd A = 0, B = 0;
      for (int i = 0; i < n; ++i) {
        A += a[i] * std::polar(1.0, -2 * std::numbers::pi * k * i / n);
        B += b[i] * std::polar(1.0, -2 * std::numbers::pi * k * i / n);
      }
      suu[k] += std::norm(A);
      syy[k] += std::norm(B);
      suy[k] += std::conj(A) * B;
    }
  }
  ASSERT_EQ(r.num_averages, segs);
  double sw2 = 0;
  for (double v : w) sw2 += v * v;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    const int bin = static_cast<int>(std::lround(r.f_hz[k] * n / fs));
    EXPECT_LT(std::abs(r.H[k] - suy[bin] / suu[bin]) / std::abs(r.H[k]), 1e-10);
    EXPECT_NEAR(r.coherence[k], std::norm(suy[bin]) / (suu[bin] * syy[bin]), 1e-10);
    const double one_sided = (bin == 0 || bin == n / 2) ? 1 : 2;
    EXPECT_LT(std::abs(r.S_uu[k] - one_sided * suu[bin] / (fs * sw2 * segs)) / r.S_uu[k], 1e-10);
  }
}

TEST(Welch, StreamingInChunksEqualsOneShot) {
  const auto u = Noise(20000, 6);
  const auto y = Filter(u);
  WelchOptions o;
  o.window_length = 1000;
  o.overlap = 0.37;
  const FrequencyResponse a = EstimateFrequencyResponse(u, y, 1000, o);
  WelchEstimator est(o);
  for (size_t s = 0; s < u.size(); s += 777) {
    const size_t n = std::min<size_t>(777, u.size() - s);
    est.Push(u.data() + s, y.data() + s, n);
  }
  const FrequencyResponse b = est.Finish(1000);
  ASSERT_EQ(a.num_averages, b.num_averages);
  for (size_t k = 0; k < a.H.size(); ++k) EXPECT_EQ(a.H[k], b.H[k]);
}

TEST(Welch, RigidBodyPhaseIsAboutMinus180AtLowFrequency) {
  model::Plant p;
  p.m = 1e-3;
  p.b = 1e-4;
  model::SimulateOptions so;
  so.encoder_step_rad = 0;
  const model::SimulatedLog log = model::SimulateLog(p, so);
  WelchOptions o;
  o.fmin_hz = 2;
  o.fmax_hz = 20;
  const FrequencyResponse r = EstimateFrequencyResponse(log.torque, log.position, 1000, o);
  for (const cd& h : r.H) EXPECT_NEAR(std::abs(std::arg(h)) * 180 / std::numbers::pi, 180.0, 12.0);
  for (const cd& h : r.H) EXPECT_LT(h.real(), 0.0);
}

TEST(Welch, SimulatedLogGivesTheExactSampledResponse) {
  const model::Plant p = model::PhantomTable1();
  model::SimulateOptions so;
  so.encoder_step_rad = 0;
  const model::SimulatedLog log = model::SimulateLog(p, so);
  const FrequencyResponse r = EstimateFrequencyResponse(log.torque, log.position, 1000, WelchOptions{});
  const model::DiscreteResponse exact(model::DiscretizeZoh(p, 1e-3));
  std::vector<double> err;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] < 1 || r.coherence[k] < 0.99) continue;
    const cd g = exact.AtTheta(2 * std::numbers::pi * r.f_hz[k] / 1000);
    err.push_back(std::abs(r.H[k] - g) / std::abs(g));
  }
  ASSERT_GT(err.size(), 500u);
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() * 95 / 100], 0.02);
}

TEST(Welch, RefusesBadRequests) {
  WelchOptions o;
  o.overlap = 1.0;
  EXPECT_THROW(WelchEstimator{o}, InputError);
  o = {};
  o.window_length = 8;
  EXPECT_THROW(WelchEstimator{o}, InputError);
  o = {};
  const auto u = Noise(1000, 1);
  try {
    EstimateFrequencyResponse(u, u, 1000, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1000 samples"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("WelchOptions::window_length 512"), std::string::npos) << e.what();
  }
  Window w;
  EXPECT_FALSE(FromString("blackman", &w));
}

TEST(Welch, DefaultOptionsAreValid) {
  std::string why;
  EXPECT_TRUE(WelchOptions{}.IsValid(&why)) << why;
}

}  // namespace
}  // namespace zwidth::ident
