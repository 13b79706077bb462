// model/cancel.h: stopping a long computation from outside, against the
// contract its header states (no check: never throws; a check that says stop:
// every later poll throws until ClearCancel; the check runs at most every
// kCancelPollSeconds per thread), counted with a check written here.
#include <atomic>
#include <chrono>

#include <gtest/gtest.h>

#include "model/cancel.h"

namespace zwidth {
namespace {

std::atomic<int> g_calls{0};
std::atomic<bool> g_stop{false};
bool CountingCheck() {
  ++g_calls;
  return g_stop.load();
}

TEST(Cancel, WithoutACheckPollingNeverThrows) {
  SetCancelCheck(nullptr);
  for (int i = 0; i < 100000; ++i) ASSERT_NO_THROW(PollCancel());
  EXPECT_FALSE(CancelRequested());
}

TEST(Cancel, AStopThrowsOnEveryPollUntilCleared) {
  g_stop = true;
  SetCancelCheck(&CountingCheck);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(4 * kCancelPollSeconds);
  bool thrown = false;
  while (!thrown && std::chrono::steady_clock::now() < until) {
    try {
      PollCancel();
    } catch (const Cancelled& c) {
      thrown = true;
      EXPECT_STREQ(c.what(), "interrupted");
    }
  }
  ASSERT_TRUE(thrown);
  EXPECT_TRUE(CancelRequested());
  g_stop = false;  // the check no longer says stop, but the request stands
  EXPECT_THROW(PollCancel(), Cancelled);
  EXPECT_THROW(PollCancel(), Cancelled);
  ClearCancel();
  EXPECT_FALSE(CancelRequested());
  EXPECT_NO_THROW(PollCancel());
  SetCancelCheck(nullptr);
}

// 0.2 s of polling in a tight loop calls the check at most 0.2 / kCancelPollSeconds
// + 1 times (one call at most per interval; the first poll always checks).
TEST(Cancel, TheCheckRunsAtMostOncePerPollInterval) {
  g_stop = false;
  g_calls = 0;
  SetCancelCheck(&CountingCheck);
  const auto t0 = std::chrono::steady_clock::now();
  long polls = 0;
  while (std::chrono::steady_clock::now() - t0 < std::chrono::duration<double>(0.2)) {
    PollCancel();
    ++polls;
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  SetCancelCheck(nullptr);
  EXPECT_GE(g_calls.load(), 1);
  EXPECT_LE(g_calls.load(), static_cast<int>(elapsed / kCancelPollSeconds) + 1);
  EXPECT_GT(polls, 10L * g_calls.load());  // many polls per check
}

}  // namespace
}  // namespace zwidth
