// The module zwidth-fit.so that the zwidth executable loads on first use
// (fit/fit_api.h): this file plus zwidth_fit and Ceres.
#include "fit/fit_api.h"
#include "zwidth_abi_hash.h"  // generated (cmake/abi_hash.cmake)

extern "C" __attribute__((visibility("default"))) const void* zwidth_fit_plugin(unsigned long long key) {
  if (key != (zwidth::fit::kFitApiKey ^ ZWIDTH_ABI_HASH)) return nullptr;  // built from other headers
  return &zwidth::fit::FitLibrary();
}
