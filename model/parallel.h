// Runs f(0), ..., f(n - 1) on up to hardware_concurrency() threads (the
// caller's among them). Each index runs at most once, in no particular order;
// once an index has thrown, the indices above it are not started. After every
// thread has joined, the exception of the lowest index that threw is rethrown,
// so the error a caller sees is the one a plain loop would have met first.
// When a thread cannot be created the work goes on with those that were.
// For independent work per delay or per start: results must be written to
// slots indexed by i, never to shared containers, so that the output does not
// depend on timing.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace zwidth {

template <class F>
void ParallelFor(size_t n, F&& f) {
  std::atomic<size_t> next{0};
  std::atomic<size_t> first_failed{n};  // the lowest index that threw so far
  std::vector<std::exception_ptr> errors(n);
  auto work = [&] {
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      if (i > first_failed.load()) continue;  // a lower index already failed
      try {
        f(i);
      } catch (...) {
        errors[i] = std::current_exception();
        size_t seen = first_failed.load();
        while (i < seen && !first_failed.compare_exchange_weak(seen, i)) {
        }
      }
    }
  };
  const size_t threads = std::min<size_t>(n, std::max(1u, std::thread::hardware_concurrency()));
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
