// io/frf_file: what WriteFrequencyResponse writes, ReadFrequencyResponse reads
// back bit for bit (CSV with %.17g, HDF5 doubles), and a damaged CSV row is
// refused by its line. Responses: seeded random values (mt19937_64, seed 7) on
// an increasing frequency grid below Nyquist.
#include <cmath>
#include <fstream>
#include <random>
#include <string>
#include <system_error>


#include <gtest/gtest.h>

#include "io/frf_file.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {

ident::FrequencyResponse RandomResponse() {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(0.1, 1.0);
  ident::FrequencyResponse r;
  r.sample_rate_hz = 1000.0;
  r.num_averages = 13;
  r.effective_averages = 12.25;
  r.bin_correlation = 1.5;
  r.window_length = 4096;
  for (int k = 1; k <= 50; ++k) {
    r.f_hz.push_back(k * 0.244140625 * U(rng) + 9.0 * k);
    r.H.push_back({U(rng) - 0.55, U(rng) - 0.55});
    r.coherence.push_back(U(rng));
    r.H_std.push_back(1e-3 * U(rng));
    r.S_uu.push_back(U(rng));
    r.S_yy.push_back(U(rng));
  }
  return r;
}

class FrfFileRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(FrfFileRoundTrip, ReadsBackWhatItWroteBitForBit) {
  const ident::FrequencyResponse r = RandomResponse();
  const test::TempDir dir("zwidth_frf_file_test_");
  const std::string path = dir / ("frf." + GetParam());
  WriteFrequencyResponse(path, r);
  EXPECT_TRUE(IsFrequencyResponseFile(path));
  const ident::FrequencyResponse q = ReadFrequencyResponse(path);
  ASSERT_EQ(q.f_hz.size(), r.f_hz.size());
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    EXPECT_EQ(q.f_hz[k], r.f_hz[k]) << k;
    EXPECT_EQ(q.H[k], r.H[k]) << k;
    EXPECT_EQ(q.coherence[k], r.coherence[k]) << k;
    EXPECT_EQ(q.H_std[k], r.H_std[k]) << k;
  }
  EXPECT_EQ(q.sample_rate_hz, r.sample_rate_hz);
  EXPECT_EQ(q.num_averages, r.num_averages);
  EXPECT_EQ(q.effective_averages, r.effective_averages);
  EXPECT_EQ(q.bin_correlation, r.bin_correlation);
}

INSTANTIATE_TEST_SUITE_P(Formats, FrfFileRoundTrip, ::testing::Values("csv", "h5"),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

TEST(FrfFile, ATruncatedCsvRowIsRefusedByItsLine) {
  const test::TempDir dir("zwidth_frf_file_test_");
  const std::string path = dir / "truncated.csv";
  WriteFrequencyResponse(path, RandomResponse());
  std::string text;
  {
    std::ifstream in(path);
    std::string line;
    for (int i = 0; std::getline(in, line); ++i) text += (i == 2 ? line.substr(0, line.find(',')) : line) + "\n";
  }
  std::ofstream(path) << text;
  try {
    ReadFrequencyResponse(path);
    FAIL() << "a truncated row was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3 has 1 fields"), std::string::npos) << e.what();
  }
}

TEST(FrfCsv, ADuplicatedColumnIsRefusedNotReadPastItsRow) {
  const test::TempDir dir("zwidth_frf_file_test_");
  std::string text = "f_hz,H_re,H_im,coherence,coherence,coherence,coherence\n";
  // Four distinct names, so the old reader let rows of four fields through and
  // read "coherence" at position 6: past the row's buffer.
  for (int k = 1; k <= 20; ++k) text += std::to_string(k) + ",1,0,1\n";
  test::WriteFile(dir / "frf.csv", text);
  try {
    ReadFrequencyResponse(dir / "frf.csv", 1000.0);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("column 'coherence' appears twice"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace zwidth::io
