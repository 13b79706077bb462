// FitLibrary() of the static library zwidth_fit: the real functions (see
// fit/fit_api.h; the zwidth executable defines its own, from the plugin).
#include "fit/fit_api.h"

#include <glog/logging.h>

#include "ident/fft.h"

namespace zwidth::fit {

const FitApi& FitLibrary() {
  static const FitApi api = [] {
    FitApi a;
    a.fit_model_quiet = [](const ident::FrequencyResponse& frf, const FitOptions& options) {
      FLAGS_minloglevel = google::GLOG_FATAL;
      return FitModel(frf, options);
    };
    a.fit_friction_quiet = [](const std::vector<double>& input, const std::vector<double>& output, double fs,
                              const FitResult& linear, const FitOptions& options, const FrictionFitOptions& friction) {
      FLAGS_minloglevel = google::GLOG_FATAL;
      return FitFriction(input, output, fs, linear, options, friction);
    };
    a.share_fftw_planner_mutex = &ident::ShareFftwPlannerMutex;
    return a;
  }();
  return api;
}

}  // namespace zwidth::fit
