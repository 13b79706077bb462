// FFTW plans shared by the estimators of ident/ (not installed: include only
// from ident/*.cc).
#pragma once

#include <map>
#include <mutex>

#include <fftw3.h>

#include "ident/fft.h"

namespace zwidth::ident::internal {

// One r2c plan per length, made once and shared, under ident::FftwPlannerMutex
// (ident/fft.h; executing a plan on new arrays is thread-safe when they have
// the alignment fftw_alloc_* gives).
struct PlanCache {
  std::map<int, fftw_plan> plans, inverse_plans;  // r2c; c2r (ident::InverseReal)
  ~PlanCache() {
    for (auto& [n, plan] : plans) fftw_destroy_plan(plan);
    for (auto& [n, plan] : inverse_plans) fftw_destroy_plan(plan);
    fftw_cleanup();
  }
  static PlanCache& Get() {
    static PlanCache cache;
    return cache;
  }
  fftw_plan For(int n, double* in, fftw_complex* out) {
    return Cached(&plans, n, [&] { return fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE); }, nullptr);
  }
  // The c2r plan of length n (it overwrites its input, as every c2r plan).
  // Past kMaxCachedLengths lengths (ident::InverseReal's are a log's, which
  // a batch of logs varies) the plan is the caller's (*owned = true), made
  // for this call and destroyed by it under FftwPlannerMutex: a cached plan
  // keeps its twiddles, 16 bytes a sample.
  fftw_plan InverseFor(int n, fftw_complex* in, double* out, bool* owned) {
    return Cached(&inverse_plans, n, [&] { return fftw_plan_dft_c2r_1d(n, in, out, FFTW_ESTIMATE); }, owned);
  }
  // The r2c plan as InverseFor (the forward cache also holds Welch's windows).
  fftw_plan ForwardFor(int n, double* in, fftw_complex* out, bool* owned) {
    return Cached(&plans, n, [&] { return fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE); }, owned);
  }
  static constexpr size_t kMaxCachedLengths = 16;

 private:
  // owned == nullptr: always cached (Welch's few window lengths).
  template <class Make>
  fftw_plan Cached(std::map<int, fftw_plan>* cache, int n, Make make, bool* owned) {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    if (owned) *owned = false;
    auto it = cache->find(n);
    if (it != cache->end()) return it->second;
    fftw_plan p = make();
    if (owned && cache->size() >= kMaxCachedLengths) {
      *owned = true;
      return p;
    }
    (*cache)[n] = p;
    return p;
  }
};

}  // namespace zwidth::ident::internal
