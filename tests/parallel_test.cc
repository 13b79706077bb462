// model/parallel.h: ParallelFor runs each index once, writes land in their
// slots, and the exception reported is the lowest index's, as a plain loop's.
#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/parallel.h"

namespace zwidth {
namespace {

TEST(ParallelFor, RunsEveryIndexOnceAndNothingForZero) {
  for (size_t n : {0u, 1u, 2u, 3u, 17u, 1000u}) {
    std::vector<std::atomic<int>> runs(n);
    std::vector<double> out(n, -1.0);
    ParallelFor(n, [&](size_t i) {
      ++runs[i];
      out[i] = 0.5 * static_cast<double>(i);
    });
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(runs[i].load(), 1) << "n=" << n << " i=" << i;
      EXPECT_EQ(out[i], 0.5 * static_cast<double>(i));
    }
  }
}

TEST(ParallelFor, RethrowsTheLowestFailingIndexLikeAPlainLoop) {
  for (int trial = 0; trial < 50; ++trial) {  // timing varies between trials; the answer must not
    try {
      ParallelFor(40, [](size_t i) {
        if (i == 7 || i == 3 || i == 31) throw std::runtime_error("index " + std::to_string(i));
      });
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "index 3");
    }
  }
}

TEST(ParallelFor, IndicesBelowAFailureStillRun) {
  std::vector<std::atomic<int>> runs(64);
  EXPECT_THROW(ParallelFor(64, [&](size_t i) {
                 ++runs[i];
                 if (i == 40) throw std::logic_error("40");
               }),
               std::logic_error);
  for (size_t i = 0; i <= 40; ++i) EXPECT_EQ(runs[i].load(), 1) << i;  // a plain loop would have run these
  for (size_t i = 41; i < 64; ++i) EXPECT_LE(runs[i].load(), 1) << i;
}

}  // namespace
}  // namespace zwidth
