#include "ident/fft.h"

#include <algorithm>
#include <atomic>

#include <fftw3.h>

#include "ident/fft_internal.h"

namespace zwidth::ident {
namespace {

std::atomic<std::mutex*> g_host{nullptr};

void DestroyPlan(fftw_plan plan) {
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  fftw_destroy_plan(plan);
}

}  // namespace

std::mutex& FftwPlannerMutex() {
  static std::mutex own;
  std::mutex* host = g_host.load(std::memory_order_acquire);
  return host ? *host : own;
}

void ShareFftwPlannerMutex(std::mutex* host) { g_host.store(host, std::memory_order_release); }

// Both through internal::PlanCache: a plan per length made once, for up to
// PlanCache::kMaxCachedLengths lengths each (planning
// even with FFTW_ESTIMATE computes the twiddle factors, sin and cos of every
// bin: 12 % of a friction fit's time when each call planned), executed on
// fftw_alloc'd copies (the alignment the shared plan needs).
std::vector<std::complex<double>> ForwardReal(std::vector<double> x) {
  const int n = static_cast<int>(x.size());
  std::vector<std::complex<double>> X(x.size() / 2 + 1);
  if (n == 0) return X;
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  std::copy(x.begin(), x.end(), in);
  bool owned = false;
  const fftw_plan plan = internal::PlanCache::Get().ForwardFor(n, in, out, &owned);
  fftw_execute_dft_r2c(plan, in, out);
  if (owned) DestroyPlan(plan);
  for (int k = 0; k <= n / 2; ++k) X[k] = {out[k][0], out[k][1]};
  fftw_free(in);
  fftw_free(out);
  return X;
}

std::vector<double> InverseReal(std::vector<std::complex<double>> X, size_t n) {
  std::vector<double> x(n);
  if (n == 0) return x;
  const int m = static_cast<int>(n);
  fftw_complex* in = fftw_alloc_complex(m / 2 + 1);
  double* out = fftw_alloc_real(m);
  for (int k = 0; k <= m / 2; ++k) {
    const std::complex<double> v = k < static_cast<int>(X.size()) ? X[k] : std::complex<double>{};
    in[k][0] = v.real();
    in[k][1] = v.imag();
  }
  bool owned = false;
  const fftw_plan plan = internal::PlanCache::Get().InverseFor(m, in, out, &owned);
  fftw_execute_dft_c2r(plan, in, out);
  if (owned) DestroyPlan(plan);
  std::copy(out, out + m, x.begin());
  fftw_free(in);
  fftw_free(out);
  return x;
}

}  // namespace zwidth::ident
