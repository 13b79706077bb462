#include "ident/fft.h"

#include <atomic>

#include <fftw3.h>

namespace zwidth::ident {
namespace {

std::atomic<std::mutex*> g_host{nullptr};

// An FFTW plan made and destroyed under FftwPlannerMutex().
class LockedPlan {
 public:
  template <class Make>
  explicit LockedPlan(Make make) {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    plan_ = make();
  }
  ~LockedPlan() {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    fftw_destroy_plan(plan_);
  }
  LockedPlan(const LockedPlan&) = delete;
  LockedPlan& operator=(const LockedPlan&) = delete;
  void Execute() const { fftw_execute(plan_); }

 private:
  fftw_plan plan_;
};

}  // namespace

std::mutex& FftwPlannerMutex() {
  static std::mutex own;
  std::mutex* host = g_host.load(std::memory_order_acquire);
  return host ? *host : own;
}

void ShareFftwPlannerMutex(std::mutex* host) { g_host.store(host, std::memory_order_release); }

std::vector<std::complex<double>> ForwardReal(std::vector<double> x) {
  std::vector<std::complex<double>> X(x.size() / 2 + 1);
  LockedPlan([&] {
    return fftw_plan_dft_r2c_1d(static_cast<int>(x.size()), x.data(), reinterpret_cast<fftw_complex*>(X.data()),
                                FFTW_ESTIMATE);
  }).Execute();
  return X;
}

std::vector<double> InverseReal(std::vector<std::complex<double>> X, size_t n) {
  std::vector<double> x(n);
  LockedPlan([&] {
    return fftw_plan_dft_c2r_1d(static_cast<int>(n), reinterpret_cast<fftw_complex*>(X.data()), x.data(), FFTW_ESTIMATE);
  }).Execute();
  return x;
}

}  // namespace zwidth::ident
