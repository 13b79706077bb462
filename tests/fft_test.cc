// ident/fft.h: the real DFT and its inverse (moved from welch_test.cc, tests
// unchanged), against the DFT sums written out in the test.
#include <complex>
#include <mutex>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ident/fft.h"

// ident/fft.h, where every FFTW plan is made: the DFT and its inverse against
// the sums written out, odd and even lengths.
TEST(Fft, ForwardAndInverseRealAreTheDftSums) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (size_t n : {1u, 2u, 7u, 16u, 45u}) {
    std::vector<double> x(n);
    for (double& v : x) v = g(rng);
    const std::vector<std::complex<double>> X = zwidth::ident::ForwardReal(x);
    ASSERT_EQ(X.size(), n / 2 + 1);
    for (size_t k = 0; k < X.size(); ++k) {
      std::complex<double> s = 0.0;
      for (size_t i = 0; i < n; ++i) s += x[i] * std::polar(1.0, -2.0 * std::numbers::pi * double(k * i) / double(n));
      EXPECT_NEAR(std::abs(X[k] - s), 0.0, 1e-12 * n) << n << " " << k;
    }
    const std::vector<double> back = zwidth::ident::InverseReal(X, n);  // n x, without the 1/n
    for (size_t i = 0; i < n; ++i) EXPECT_NEAR(back[i], double(n) * x[i], 1e-12 * n) << n << " " << i;
  }
}

// One lock per process: a copy of the library handed the host's lock uses it
// (the CLI's fit plugin, apps/plugins.cc), and nullptr gives back its own.
TEST(Fft, ACopyHandedTheHostsLockPlansUnderIt) {
  std::mutex& own = zwidth::ident::FftwPlannerMutex();
  std::mutex host;
  zwidth::ident::ShareFftwPlannerMutex(&host);
  EXPECT_EQ(&zwidth::ident::FftwPlannerMutex(), &host);
  EXPECT_EQ(zwidth::ident::ForwardReal({1.0, 2.0}).size(), 2u);  // plans under it
  zwidth::ident::ShareFftwPlannerMutex(nullptr);
  EXPECT_EQ(&zwidth::ident::FftwPlannerMutex(), &own);
}

// ident::ForwardReal / InverseReal against a plain DFT written here, on more
// lengths than their plan cache keeps (PlanCache::kMaxCachedLengths = 16): the
// lengths past it are planned for the call and destroyed after it.
TEST(Fft, ForwardAndInverseEqualAPlainDftOnFortyLengths) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  for (size_t n = 3; n < 43; ++n) {
    std::vector<double> x(n);
    for (double& v : x) v = g(rng);
    const std::vector<std::complex<double>> X = zwidth::ident::ForwardReal(x);
    ASSERT_EQ(X.size(), n / 2 + 1);
    for (size_t k = 0; k <= n / 2; ++k) {
      std::complex<double> s = 0.0;
      for (size_t i = 0; i < n; ++i) s += x[i] * std::polar(1.0, -2.0 * std::numbers::pi * double(k * i) / double(n));
      EXPECT_LT(std::abs(X[k] - s), 1e-12 * n) << "n = " << n << ", bin " << k;
    }
    const std::vector<double> back = zwidth::ident::InverseReal(X, n);  // without the 1/n
    for (size_t i = 0; i < n; ++i) EXPECT_NEAR(back[i] / double(n), x[i], 1e-12) << "n = " << n;
  }
}
