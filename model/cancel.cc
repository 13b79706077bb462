#include "model/cancel.h"

#include <atomic>
#include <chrono>

namespace zwidth {
namespace {

std::atomic<CancelCheck> g_check{nullptr};
std::atomic<bool> g_cancelled{false};

}  // namespace

void SetCancelCheck(CancelCheck check) {
  g_check.store(check);
  g_cancelled.store(false);
}

void ClearCancel() { g_cancelled.store(false); }

bool CancelRequested() { return g_cancelled.load(std::memory_order_relaxed); }

void PollCancel() {
  if (g_cancelled.load(std::memory_order_relaxed)) throw Cancelled();
  const CancelCheck check = g_check.load(std::memory_order_relaxed);
  if (!check) return;
  // The check at most every kCancelPollSeconds per thread (a clock read, ~25 ns:
  // loops of sub-microsecond steps poll every 1024th step).
  thread_local std::chrono::steady_clock::time_point last{};
  const auto now = std::chrono::steady_clock::now();
  if (now - last < std::chrono::duration<double>(kCancelPollSeconds)) return;
  last = now;
  if (check()) {
    g_cancelled.store(true);
    throw Cancelled();
  }
}

}  // namespace zwidth
