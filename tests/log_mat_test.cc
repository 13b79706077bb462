// io/log_mat.cc: MATLAB .mat logs of io/log.h (moved from log_test.cc, tests
// unchanged): files written by libmatio's writer (v5 and v7.3), read back,
// compared sample for sample with what was written.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <matio.h>

#include "io/log.h"
#include "tests/log_formats.h"

namespace zwidth::io {
namespace {


// .mat through libmatio's writer, v5 and v7.3 (HDF5), named with misleading
// extensions: the content decides.
void WriteMat(const std::string& path, mat_ft version, const Signals& s) {
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, version);
  ASSERT_NE(mat, nullptr);
  auto put = [&](const char* name, const std::vector<double>& v) {
    size_t dims[2] = {v.size(), 1};
    matvar_t* var = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, const_cast<double*>(v.data()), 0);
    ASSERT_NE(var, nullptr);
    EXPECT_EQ(Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE), 0);
    Mat_VarFree(var);
  };
  put("Time", s.t);
  put("u", s.u);
  put("Theta", s.y);
  Mat_Close(mat);
}

TEST_F(LogFormats, MatV5AndV73ByContent) {
  const Signals s = MakeSignals();
  LogSelect sel;
  sel.time_column = "Time";
  sel.input_column = "u";
  sel.output_column = "Theta";
  for (auto [version, name] : {std::pair{MAT_FT_MAT5, "v5.csv"}, std::pair{MAT_FT_MAT73, "v73.txt"}}) {
    const std::string p = dir_ / name;
    WriteMat(p, version, s);
    EXPECT_EQ(DetectLogFormat(p), LogFormat::kMat) << name;
    ExpectSame(ReadLog(p, sel), s);
    LogSelect bad = sel;
    bad.output_column = "theta";
    const std::string m = Refusal(p, bad);
    EXPECT_NE(m.find("variables: "), std::string::npos) << m;
    EXPECT_NE(m.find("Theta"), std::string::npos) << m;
  }
}

// A .mat log's time is read in s: a 10 kHz log with its time in ms (10 Hz)
// is refused with the rate to pass; 50 Hz is read with a warning.
TEST_F(LogFormats, MatTimeInMillisecondsIsRefused) {
  Signals s = MakeSignals(3000, 10000.0);
  for (double& t : s.t) t *= 1e3;
  LogSelect sel;
  sel.time_column = "Time";
  sel.input_column = "u";
  sel.output_column = "Theta";
  const std::string p = dir_ / "ms.mat";
  WriteMat(p, MAT_FT_MAT5, s);
  const std::string m = Refusal(p, sel);
  EXPECT_NE(m.find("implies 10 Hz, implausible"), std::string::npos) << m;
  EXPECT_NE(m.find("LogSelect::sample_rate_hz 1e+04"), std::string::npos) << m;
  sel.sample_rate_hz = 10000.0;
  EXPECT_EQ(ReadLog(p, sel).info.sample_rate_hz, 10000.0);
  for (double& t : s.t) t *= 0.2;  // 50 Hz
  WriteMat(p, MAT_FT_MAT5, s);
  sel.sample_rate_hz = 0.0;
  const Log log = ReadLog(p, sel);
  ASSERT_EQ(log.info.warnings.size(), 1u);
  EXPECT_NE(log.info.warnings[0].find("implies 50 Hz, low"), std::string::npos) << log.info.warnings[0];
}

}  // namespace
}  // namespace zwidth::io
