// io/io_internal.h's text output (io/text_out.cc): AppendG against the C
// library's printf("%.*g") (another implementation of the same format) on
// 40 000 seeded doubles over 600 decades, every precision 1..17 and the
// special values; AppendInt against "%lld"; CsvFile's bytes against the
// string the test expects, and its two refusals.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "io/io_internal.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io::internal {
namespace {

std::string Printf(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

TEST(TextOut, AppendGIsPrintfsG) {
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> e(-300.0, 300.0), u(1.0, 10.0);
  std::uniform_int_distribution<int> dig(1, 17), sign(0, 1);
  for (int k = 0; k < 40000; ++k) {
    const double v = (sign(rng) ? -1.0 : 1.0) * u(rng) * std::pow(10.0, std::floor(e(rng)));
    const int d = dig(rng);
    std::string got;
    AppendG(&got, v, d);
    ASSERT_EQ(got, Printf(v, d)) << "v = " << Printf(v, 17) << ", digits " << d;
  }
  const double specials[] = {0.0, -0.0, 1.0, 0.5, 9.5, 99.95, 123456.0, 1e16, 1e-5, 1e-4, 5e-324,
                             std::numeric_limits<double>::max(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity()};
  for (double v : specials) {
    for (int d = 1; d <= 17; ++d) {
      std::string got;
      AppendG(&got, v, d);
      EXPECT_EQ(got, Printf(v, d)) << v << " " << d;
    }
  }
  std::string nan;
  AppendG(&nan, std::numeric_limits<double>::quiet_NaN(), 6);
  EXPECT_EQ(nan, Printf(std::numeric_limits<double>::quiet_NaN(), 6));
}

TEST(TextOut, AppendIntIsPrintfsLld) {
  for (long long v : {0LL, 7LL, -7LL, 1234567890123LL, std::numeric_limits<long long>::max(),
                      std::numeric_limits<long long>::min()}) {
    std::string got = "x";
    AppendInt(&got, v);
    char b[32];
    std::snprintf(b, sizeof b, "x%lld", v);
    EXPECT_EQ(got, b);
  }
}

TEST(TextOut, CsvFileWritesItsLinesAndSaysWhenItCannot) {
  const test::TempDir dir("zwidth_text_out_");
  const std::string path = (dir.path() / "a.csv").string();
  {
    CsvFile f(path);
    f.Text("f_hz,H");
    f.End();
    for (int i = 0; i < 3; ++i) {
      f.Int(i).G(0.1 * i, 6);
      f.End();
    }
    f.Close("a.csv");
  }
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes, "f_hz,H\n0,0\n1,0.1\n2,0.2\n");
  EXPECT_THROW(CsvFile((dir.path() / "no" / "such" / "b.csv").string()), InputError);
  if (std::filesystem::exists("/dev/full")) {
    CsvFile full("/dev/full");
    full.Text("x");
    full.End();
    try {
      full.Close("full.csv");
      ADD_FAILURE() << "a failed write was not reported";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("failed writing 'full.csv'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace zwidth::io::internal
