// ident/excitation.h: the rig's input signals against independent references:
// the Schroeder multisine against its sum of cosines written out (lines
// k f0, phases -pi k (k - 1) / K, amplitude rms sqrt(2 / K)); the noise's
// spectrum against a plain DFT written here (no power outside the band); the
// chirp's zero crossings against its instantaneous frequency f(t) = fmin
// (fmax / fmin)^(t / T); the crest factor and the band fraction against
// signals whose values are known (a sine: sqrt 2; tones of known power).
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ident/excitation.h"
#include "model/error.h"

namespace zwidth::ident {
namespace {

ExcitationOptions Options(ExcitationKind kind, double seconds, double rate_hz, double fmin_hz, double fmax_hz,
                          double rms = 0.03) {
  ExcitationOptions o;
  o.kind = kind;
  o.seconds = seconds;
  o.sample_rate_hz = rate_hz;
  o.fmin_hz = fmin_hz;
  o.fmax_hz = fmax_hz;
  o.rms = rms;
  return o;
}

double RmsOf(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v * v;
  return std::sqrt(s / x.size());
}

TEST(Excitation, MultisineIsItsSumOfSchroederCosines) {
  const ExcitationOptions o = Options(ExcitationKind::kMultisine, 4.0, 1000.0, 2.0, 60.0, 0.05);
  const Excitation e = MakeExcitation(o);
  // f0 = fmin: P = 500 samples, 8 periods in 4 s, lines 1..30 of f0.
  ASSERT_EQ(e.period_samples, 500);
  ASSERT_EQ(e.num_periods, 8);
  ASSERT_EQ(e.num_lines, 30);
  EXPECT_DOUBLE_EQ(e.line_spacing_hz, 2.0);
  ASSERT_EQ(e.signal.size(), 4000u);
  const int K = 30, P = 500;
  const double amp = o.rms * std::sqrt(2.0 / K);
  for (int t = 0; t < 4000; ++t) {
    double want = 0.0;
    for (int k = 1; k <= K; ++k) {
      want += amp * std::cos(2 * std::numbers::pi * k * (t % P) / P - std::numbers::pi * k * (k - 1.0) / K);
    }
    EXPECT_NEAR(e.signal[t], want, 1e-13) << t;
  }
  EXPECT_NEAR(e.rms, o.rms, 1e-15);
  EXPECT_NEAR(e.band_power_fraction, 1.0, 1e-12);
  // Schroeder's phases keep the crest factor low (~1.4-1.7 for 30 lines; random ~3).
  EXPECT_LT(e.crest_factor, 2.0);
}

TEST(Excitation, NoiseHasNoPowerOutsideItsBand) {
  ExcitationOptions o = Options(ExcitationKind::kNoise, 1.0, 1000.0, 20.0, 80.0, 0.2);
  o.seed = 3;
  const Excitation e = MakeExcitation(o);
  const size_t n = e.signal.size();
  ASSERT_EQ(n, 1000u);
  EXPECT_NEAR(RmsOf(e.signal), 0.2, 1e-14);
  double in = 0.0, out = 0.0;
  for (size_t k = 0; k <= n / 2; ++k) {  // the DFT written out, bin k at k Hz
    std::complex<double> X = 0.0;
    for (size_t i = 0; i < n; ++i) X += e.signal[i] * std::polar(1.0, -2 * std::numbers::pi * double(k * i) / n);
    (k >= 20 && k <= 80 ? in : out) += std::norm(X);
  }
  EXPECT_LT(out, 1e-24 * in);
  EXPECT_NEAR(e.band_power_fraction, 1.0, 1e-12);
  // Another seed, another signal.
  o.seed = 4;
  EXPECT_NE(MakeExcitation(o).signal[10], e.signal[10]);
}

// Between two zero crossings of sin(phi(t)) half a cycle passes: the crossing
// spacing dt gives f ~ 1 / (2 dt), which must match f(t) at the midpoint.
TEST(Excitation, ChirpFollowsItsLogarithmicFrequency) {
  const ExcitationOptions o = Options(ExcitationKind::kChirp, 10.0, 10000.0, 1.0, 100.0);
  const Excitation e = MakeExcitation(o);
  const double fs = o.sample_rate_hz, T = e.signal.size() / fs;
  std::vector<double> crossings;
  for (size_t i = 1; i < e.signal.size(); ++i) {
    const double a = e.signal[i - 1], b = e.signal[i];
    if ((a < 0) != (b < 0)) crossings.push_back((i - 1 + a / (a - b)) / fs);  // linear interpolation
  }
  ASSERT_GT(crossings.size(), 100u);
  int checked = 0;
  for (size_t j = 1; j < crossings.size(); ++j) {
    const double mid = 0.5 * (crossings[j] + crossings[j - 1]);
    if (mid < 0.5) continue;
    const double want = o.fmin_hz * std::pow(o.fmax_hz / o.fmin_hz, mid / T);
    EXPECT_NEAR(0.5 / (crossings[j] - crossings[j - 1]), want, 2e-3 * want) << mid;
    ++checked;
  }
  EXPECT_GT(checked, 100);
  EXPECT_NEAR(e.rms, o.rms, 1e-15);
}

TEST(Excitation, CrestFactorAndBandPowerOfKnownSignals) {
  const int n = 1000;
  const double fs = 1000.0;
  std::vector<double> sine(n), square(n), two(n);
  for (int i = 0; i < n; ++i) {
    sine[i] = std::sin(2 * std::numbers::pi * 10 * i / fs + 0.25);  // a whole number of cycles
    square[i] = (i / 50) % 2 ? 1.0 : -1.0;
    two[i] = 3.0 * std::cos(2 * std::numbers::pi * 10 * i / fs) + 4.0 * std::cos(2 * std::numbers::pi * 200 * i / fs);
  }
  EXPECT_NEAR(CrestFactor(sine), std::sqrt(2.0), 1e-4);  // the sampled peak is within 1e-4 of 1
  EXPECT_DOUBLE_EQ(CrestFactor(square), 1.0);
  EXPECT_NEAR(BandPowerFraction(sine, fs, 5.0, 20.0), 1.0, 1e-12);
  EXPECT_NEAR(BandPowerFraction(sine, fs, 11.0, 20.0), 0.0, 1e-12);
  EXPECT_NEAR(BandPowerFraction(two, fs, 0.0, 50.0), 9.0 / 25.0, 1e-12);  // 3^2 / (3^2 + 4^2)
  EXPECT_NEAR(BandPowerFraction(two, fs, 100.0, 499.0), 16.0 / 25.0, 1e-12);
}

TEST(Excitation, BadOptionsAreRefusedByName) {
  std::string why;
  EXPECT_TRUE(ExcitationOptions{}.IsValid(&why)) << why;
  struct Case { ExcitationOptions o; const char* field; };
  std::vector<Case> cases;
  ExcitationOptions o;
  o.sample_rate_hz = 0.0; cases.push_back({o, "sample_rate_hz"});
  o = {}; o.seconds = -1.0; cases.push_back({o, "seconds"});
  o = {}; o.rms = std::nan(""); cases.push_back({o, "rms"});
  o = {}; o.fmax_hz = 600.0; cases.push_back({o, "fmax_hz"});
  o = {}; o.fmax_hz = 0.4; cases.push_back({o, "fmax_hz"});
  o = {}; o.kind = ExcitationKind::kChirp; o.fmin_hz = 0.0; cases.push_back({o, "fmin_hz"});
  for (const Case& c : cases) {
    EXPECT_FALSE(c.o.IsValid(&why)) << c.field;
    EXPECT_NE(why.find(c.field), std::string::npos) << why;
    EXPECT_THROW(MakeExcitation(c.o), InputError) << c.field;
  }
  for (ExcitationKind k : {ExcitationKind::kNoise, ExcitationKind::kMultisine, ExcitationKind::kChirp}) {
    ExcitationKind back;
    ASSERT_TRUE(FromString(ToString(k), &back));
    EXPECT_EQ(back, k);
  }
  ExcitationKind k;
  EXPECT_FALSE(FromString("sweep", &k));
}

}  // namespace
}  // namespace zwidth::ident
