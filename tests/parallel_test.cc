// model/parallel.h: ParallelFor runs each index once, writes land in their
// slots, and the exception reported is the lowest index's, as a plain loop's.
#include <sched.h>
#include <stdlib.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/error.h"
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

// The threads a ParallelFor used: distinct ids seen over n slow items.
size_t ThreadsUsed(size_t n) {
  std::mutex mu;
  std::set<std::thread::id> ids;
  ParallelFor(n, [&](size_t) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::lock_guard<std::mutex> lock(mu);
    ids.insert(std::this_thread::get_id());
  });
  return ids.size();
}

TEST(ParallelFor, ThreadsFollowSetNumThreadsThenTheEnvironmentThenTheCores) {
  SetNumThreads(1);
  EXPECT_EQ(ThreadsUsed(16), 1u);
  SetNumThreads(2);
  EXPECT_EQ(ThreadsUsed(16), 2u);
  SetNumThreads(0);
  setenv("ZWIDTH_NUM_THREADS", "1", 1);
  EXPECT_EQ(NumThreads(), 1);
  EXPECT_EQ(ThreadsUsed(16), 1u);
  for (const char* bad : {"0", "-2", "two", "3x", "99999"}) {
    setenv("ZWIDTH_NUM_THREADS", bad, 1);
    EXPECT_THROW(NumThreads(), InputError) << bad;
  }
  unsetenv("ZWIDTH_NUM_THREADS");
  cpu_set_t set;
  ASSERT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
  EXPECT_LE(NumThreads(), CPU_COUNT(&set));  // the affinity mask bounds the default
  EXPECT_GE(NumThreads(), 1);
  EXPECT_THROW(SetNumThreads(-1), InputError);
}

TEST(ParallelFor, AScopedSerialThreadRunsItsLoopsAloneAndOtherThreadsAsBefore) {
  SetNumThreads(3);
  {
    ScopedSerialThread serial;
    EXPECT_EQ(NumThreads(), 1);
    EXPECT_EQ(ThreadsUsed(16), 1u);
    {
      ScopedSerialThread nested;
      EXPECT_EQ(NumThreads(), 1);
    }
    EXPECT_EQ(NumThreads(), 1);  // the outer scope still holds
    int elsewhere = 0;
    std::thread([&] { elsewhere = NumThreads(); }).join();
    EXPECT_EQ(elsewhere, 3);  // per thread only
  }
  EXPECT_EQ(NumThreads(), 3);
  EXPECT_EQ(ThreadsUsed(16), 3u);
  SetNumThreads(0);
}

TEST(ParallelFor, StopsEveryThreadWhenTheCancelCheckSaysSo) {
  static std::atomic<int> checks{0};
  SetCancelCheck([] { return ++checks >= 3; });
  std::atomic<int> started{0};
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_THROW(ParallelFor(100000, [&](size_t) {
                 ++started;
                 std::this_thread::sleep_for(std::chrono::milliseconds(1));
               }),
               Cancelled);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(s, 1.0);  // 3 checks at most kCancelPollSeconds apart, not 100000 items
  EXPECT_LT(started.load(), 100000);
  EXPECT_TRUE(CancelRequested());
  ClearCancel();
  SetCancelCheck(nullptr);
  EXPECT_NO_THROW(ParallelFor(10, [](size_t) {}));  // no check: never cancelled
}

}  // namespace
}  // namespace zwidth
