// Shared by the log readers' tests (log_text_test.cc, log_mat_test.cc):
// seeded signals, exact number printing and a fixture that writes files into a
// temporary folder and reads them back. Not in an anonymous namespace: one
// fixture type across the files of the executable, as googletest requires of
// a test suite (LogFormats); inline, so each file may include it.
#pragma once

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io/log.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {

struct Signals {
  std::vector<double> t, u, y;
};

inline Signals MakeSignals(size_t n = 3000, double rate = 1000.0) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> g(0.0, 1.0);
  Signals s;
  double acc = 0;
  for (size_t k = 0; k < n; ++k) {
    s.t.push_back(k / rate);
    s.u.push_back(0.03 * g(rng));
    acc += s.u.back();
    s.y.push_back(1e-3 * acc);
  }
  return s;
}

inline std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

class LogFormats : public ::testing::Test {
 protected:
  std::string Write(const std::string& name, const std::string& bytes) { return dir_.Write(name, bytes); }
  // Rows "t<d>u<d>y" with the given line end; time scaled by time_factor.
  static std::string Rows(const Signals& s, const std::string& d, const std::string& eol, double time_factor = 1.0) {
    std::string out;
    for (size_t k = 0; k < s.u.size(); ++k) out += Num(s.t[k] * time_factor) + d + Num(s.u[k]) + d + Num(s.y[k]) + eol;
    return out;
  }
  static void ExpectSame(const Log& log, const Signals& s, double u_scale = 1.0, double y_scale = 1.0) {
    ASSERT_EQ(log.input.size(), s.u.size());
    for (size_t k = 0; k < s.u.size(); ++k) {
      ASSERT_EQ(log.input[k], s.u[k] * u_scale) << "sample " << k;
      ASSERT_EQ(log.output[k], s.y[k] * y_scale) << "sample " << k;
    }
    EXPECT_NEAR(log.info.sample_rate_hz, 1000.0, 1e-6);
  }
  // The message of the InputError that reading throws.
  std::string Refusal(const std::string& path, const LogSelect& sel) {
    try {
      ReadLog(path, sel);
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_EQ(m.find('\r'), std::string::npos) << m;
      EXPECT_LT(m.size(), 600u) << m;
      return m;
    }
    ADD_FAILURE() << path << " was accepted";
    return "";
  }
  test::TempDir dir_{"zwidth_logfmt_"};
};

}  // namespace zwidth::io
