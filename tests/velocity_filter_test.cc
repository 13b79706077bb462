// stability/velocity_filter.h and velocity_filter_internal.h: the loop's
// low-pass and the filter in the time domain, against independent references:
// the low-pass's coefficients from its formula and its DC gain; the time-domain
// filter's impulse response against the closed form (1 - a) a^k, and its
// steady-state response to a sinusoid against F(e^{j theta}) evaluated from
// the coefficients as a ratio of polynomials in z^-1.
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/error.h"
#include "stability/loop_options.h"
#include "stability/velocity_filter.h"
#include "stability/velocity_filter_internal.h"

namespace zwidth::stability {
namespace {

using cd = std::complex<double>;

// F(e^{j theta}) = sum b_i z^-i / sum a_i z^-i, evaluated term by term.
cd FilterAt(const LoopOptions& l, double theta) {
  if (!l.HasFilter()) return 1.0;
  cd nb = 0.0, na = 0.0;
  for (size_t i = 0; i < l.filter_b.size(); ++i) nb += l.filter_b[i] * std::polar(1.0, -theta * double(i));
  for (size_t i = 0; i < l.filter_a.size(); ++i) na += l.filter_a[i] * std::polar(1.0, -theta * double(i));
  return nb / na;
}

TEST(VelocityFilter, LowPassIsTheFirstOrderFormulaWithUnitDcGain) {
  for (double T : {1e-3, 1e-4}) {
    for (double fc : {1.0, 30.0, 0.2 / T, 0.499 / T}) {
      LoopOptions l;
      SetLowPassFilter(fc, T, &l);
      const double a = std::exp(-2.0 * std::numbers::pi * fc * T);
      ASSERT_EQ(l.filter_b.size(), 1u);
      ASSERT_EQ(l.filter_a.size(), 2u);
      EXPECT_DOUBLE_EQ(l.filter_b[0], 1.0 - a);
      EXPECT_DOUBLE_EQ(l.filter_a[0], 1.0);
      EXPECT_DOUBLE_EQ(l.filter_a[1], -a);
      EXPECT_NEAR(std::abs(FilterAt(l, 0.0)), 1.0, 1e-14);
      // The magnitude falls with frequency (a low-pass) and is that of the
      // one-pole formula |1 - a| / |1 - a e^{-j theta}| at Nyquist: (1 - a)/(1 + a).
      EXPECT_NEAR(std::abs(FilterAt(l, std::numbers::pi)), (1 - a) / (1 + a), 1e-14);
      std::string why;
      EXPECT_TRUE(l.IsValid(&why)) << why;
    }
  }
}

TEST(VelocityFilter, LowPassRefusesCutoffsOutsideZeroToNyquist) {
  LoopOptions l;
  for (double fc : {0.0, -5.0, 500.0, 800.0, std::nan("")}) {
    try {
      SetLowPassFilter(fc, 1e-3, &l);
      ADD_FAILURE() << fc << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cutoff_hz"), std::string::npos) << e.what();
    }
  }
}

TEST(VelocityFilter, ImpulseResponseOfTheLowPassIsGeometric) {
  LoopOptions l;
  SetLowPassFilter(40.0, 1e-3, &l);
  const double a = std::exp(-2.0 * std::numbers::pi * 40.0 * 1e-3);
  internal::VelocityFilter f(l);
  for (int k = 0; k < 200; ++k) {
    const double w = f.Step(k == 0 ? 1.0 : 0.0);
    EXPECT_NEAR(w, (1 - a) * std::pow(a, k), 1e-15) << k;
  }
}

// A sinusoid of frequency theta through the filter, after its transient has
// died (poles of modulus <= 0.8: 0.8^400 ~ 1e-39), is |F| cos(theta k + arg F).
TEST(VelocityFilter, SteadyStateSinusoidIsScaledAndShiftedByTheResponse) {
  LoopOptions low, second, fir, none;
  SetLowPassFilter(60.0, 1e-3, &low);
  second.filter_b = {0.05, 0.2, -0.03};
  second.filter_a = {1.0, -1.1, 0.45};  // poles at radius sqrt(0.45) = 0.67
  fir.filter_b = {0.5, 0.5};
  fir.filter_a = {1.0};
  for (const LoopOptions* l : {&low, &second, &fir, &none}) {
    for (double th : {0.01, 0.3, 1.2, 2.9}) {
      internal::VelocityFilter f(*l);
      const cd F = FilterAt(*l, th);
      for (int k = 0; k < 600; ++k) {
        const double w = f.Step(std::cos(th * k));
        if (k >= 400) EXPECT_NEAR(w, std::abs(F) * std::cos(th * k + std::arg(F)), 1e-12) << th << " " << k;
      }
    }
  }
}

}  // namespace
}  // namespace zwidth::stability
