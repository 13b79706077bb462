// FitLibrary() of the static library zwidth_fit: the real functions (see
// fit/fit_api.h; the zwidth executable defines its own, from the plugin).
#include "fit/fit_api.h"

#include <glog/logging.h>

namespace zwidth::fit {

const FitApi& FitLibrary() {
  static const FitApi api = [] {
    FitApi a;
    a.fit_model_quiet = [](const ident::FrequencyResponse& frf, const FitOptions& options) {
      FLAGS_minloglevel = google::GLOG_FATAL;
      return FitModel(frf, options);
    };
    return a;
  }();
  return api;
}

}  // namespace zwidth::fit
