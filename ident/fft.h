// FFTW in one place: every FFTW plan of zwidth is made and destroyed by this
// module (ident/fft.cc), under one lock, since FFTW's planner is not
// thread-safe (executing a plan is, on arrays with fftw_alloc_*'s alignment).
// A Welch estimate, an excitation and a friction fit may then run on threads
// side by side (batch units, Python threads).
#pragma once

#include <complex>
#include <cstddef>
#include <mutex>
#include <vector>

namespace zwidth::ident {

// The DFT of a real sequence: bins 0..n/2 of X_k = sum_i x_i e^{-2 pi j k i / n}.
std::vector<std::complex<double>> ForwardReal(std::vector<double> x);
// Its inverse without the 1/n: x_i = sum over all bins of X_k e^{2 pi j k i / n},
// from the one-sided X[0..n/2] (FFTW's c2r; X is its scratch).
std::vector<double> InverseReal(std::vector<std::complex<double>> X, size_t n);

// Held around every call of FFTW's planner (fftw_plan_*, fftw_destroy_plan):
// by this module's plans and its cache of Welch's plans (ident/fft_internal.h).
// One per process: a copy of this library inside a plugin (the CLI's fit
// plugin, fit/fit_api.h) is handed the host's by ShareFftwPlannerMutex.
std::mutex& FftwPlannerMutex();
// This copy of the library takes `host`'s lock instead of its own (nullptr:
// its own again). Called once by the plugin's loader before any of the
// plugin's code runs (apps/plugins.cc); `host` must outlive every plan.
void ShareFftwPlannerMutex(std::mutex* host);

}  // namespace zwidth::ident
