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
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    auto it = plans.find(n);
    if (it != plans.end()) return it->second;
    fftw_plan p = fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
    plans[n] = p;
    return p;
  }
  // The c2r plan of length n (it overwrites its input, as every c2r plan).
  fftw_plan InverseFor(int n, fftw_complex* in, double* out) {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    auto it = inverse_plans.find(n);
    if (it != inverse_plans.end()) return it->second;
    fftw_plan p = fftw_plan_dft_c2r_1d(n, in, out, FFTW_ESTIMATE);
    inverse_plans[n] = p;
    return p;
  }
};

}  // namespace zwidth::ident::internal
