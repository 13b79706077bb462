// Runs f(0), ..., f(n - 1) on up to NumThreads() threads (the caller's among
// them). Each index runs at most once, in no particular order;
// once an index has thrown, the indices above it are not started. After every
// thread has joined, the exception of the lowest index that threw is rethrown,
// so the error a caller sees is the one a plain loop would have met first.
// When a thread cannot be created the work goes on with those that were.
// For independent work per delay or per start: results must be written to
// slots indexed by i, never to shared containers, so that the output does not
// depend on timing. Each item starts with PollCancel() (model/cancel.h).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#include "model/cancel.h"

namespace zwidth {

// The cores this process may run on: its affinity mask (taskset, cpusets)
// capped by a cgroup CPU quota (containers), at least 1.
int AvailableCpus();
// Threads of a ParallelFor: SetNumThreads(n > 0) if called (the Python
// module's set_num_threads), else the environment's ZWIDTH_NUM_THREADS (a
// whole number >= 1; anything else is an InputError), else AvailableCpus().
// SetNumThreads(0) returns to the default; n < 0 is an InputError.
// ScopedSerialThread (below) makes it 1 on its thread.
void SetNumThreads(int n);
int NumThreads();

// While one lives, NumThreads() is 1 on the thread that made it (and only
// there): a ParallelFor it calls runs on that thread alone. A batch that runs
// one unit per thread (analysis/batch.h) keeps the process at its own count
// of threads this way instead of each unit's ParallelFor adding its own.
class ScopedSerialThread {
 public:
  ScopedSerialThread();
  ~ScopedSerialThread();
  ScopedSerialThread(const ScopedSerialThread&) = delete;
  ScopedSerialThread& operator=(const ScopedSerialThread&) = delete;

 private:
  bool was_serial_;
};

template <class F>
void ParallelFor(size_t n, F&& f) {
  std::atomic<size_t> next{0};
  std::atomic<size_t> first_failed{n};  // the lowest index that threw so far
  std::vector<std::exception_ptr> errors(n);
  auto work = [&] {
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      if (i > first_failed.load()) continue;  // a lower index already failed
      try {
        PollCancel();
        f(i);
      } catch (...) {
        errors[i] = std::current_exception();
        size_t seen = first_failed.load();
        while (i < seen && !first_failed.compare_exchange_weak(seen, i)) {
        }
      }
    }
  };
  const size_t threads = std::min<size_t>(n, static_cast<size_t>(NumThreads()));
  std::vector<std::jthread> pool;
  for (size_t t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads: the ones running and this one do the rest
    }
  }
  work();
  pool.clear();  // joins
  if (first_failed.load() < n) std::rethrow_exception(errors[first_failed.load()]);
}

}  // namespace zwidth
