// The fit's entry points behind one table of function pointers (internal: not
// installed). The static library zwidth_fit defines FitLibrary() in
// fit/fit_api.cc as the real functions; the zwidth executable defines its own
// (apps/plugins.cc), which loads the module zwidth-fit.so (fit/fit_plugin.cc)
// on first use: Ceres and what it brings (glog, cholmod, LAPACK, BLAS,
// gfortran: ~28 shared libraries, ~5 ms per process start) are then mapped
// only by the commands that fit. See io/hdf5_api.h for the same seam of HDF5.
#pragma once

#include <mutex>

#include "fit/fit.h"
#include "fit/friction_fit.h"

namespace zwidth::fit {

struct FitApi {
  // fit::FitModel with Ceres' glog output off the terminal (only fatal
  // messages): what matters reaches the fit's warnings and quality reasons.
  FitResult (*fit_model_quiet)(const ident::FrequencyResponse& frf, const FitOptions& options) = nullptr;
  // fit::FitFriction, glog quiet alike.
  FrictionFitResult (*fit_friction_quiet)(const std::vector<double>& input, const std::vector<double>& output,
                                          double sample_rate_hz, const FitResult& linear, const FitOptions& options,
                                          const FrictionFitOptions& friction) = nullptr;
  // ident::ShareFftwPlannerMutex of the table's copy of the library: the
  // plugin's loader hands it the host's lock (ident/fft.h) before any call,
  // so one lock guards FFTW's planner in the whole process.
  void (*share_fftw_planner_mutex)(std::mutex* host) = nullptr;
};

// Changes whenever a type crossing the table changes size; mixed with
// ZWIDTH_ABI_HASH (cmake/abi_hash.cmake) by the executable and the plugin, so
// a plugin built from other headers is refused even with the same sizes.
inline constexpr unsigned long long kFitApiKey = (2ull << 56) ^ (sizeof(FitApi) << 40) ^
                                                 (sizeof(FitOptions) << 24) ^ (sizeof(FitResult) << 8) ^
                                                 sizeof(ident::FrequencyResponse) ^ (sizeof(FrictionFitResult) << 32);

// The table: the real functions (zwidth_fit), or the plugin's, loaded on
// first call (the zwidth executable; a missing or broken plugin is a
// ComputationError naming the file).
const FitApi& FitLibrary();

}  // namespace zwidth::fit
