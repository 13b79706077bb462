// A log to a model to its Z-width, the route of `zwidth run` in a few calls:
// the log's frequency response (Welch), the fit of eq. (1) with its verdict,
// the model file, and the Z-width per loop delay.
//
//   log_to_zwidth LOG MODEL_OUT.json [NUM_MODES]     (default: 2 sections)
//   LOG: a text log (time, input, output columns); .h5/.mat logs need
//   zwidth::hdf5 linked as well (find_package(zwidth COMPONENTS hdf5)).
#include <cstdio>
#include <cstdlib>
#include <string>

#include <zwidth/analysis/logs_estimate.h>
#include <zwidth/fit/fit.h>
#include <zwidth/io/fit_file.h>
#include <zwidth/io/model_json.h>
#include <zwidth/stability/zwidth.h>

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 3, "LOG MODEL_OUT.json [NUM_MODES]", [&] {
    zwidth::analysis::LogsEstimateOptions estimate_options;
    estimate_options.for_fit = true;
    const zwidth::analysis::LogsEstimate estimate = zwidth::analysis::EstimateFromLogs({argv[1]}, estimate_options);
    const zwidth::ident::FrequencyResponse& frf = estimate.response.frf;

    zwidth::fit::FitOptions fit_options;
    if (argc > 3) fit_options.num_modes = std::atoi(argv[3]);
    const zwidth::fit::FitResult fit = zwidth::fit::FitModel(frf, fit_options);
    std::printf("%s\n", fit.BriefReport().c_str());
    if (fit.status != zwidth::fit::FitStatus::kConverged) return 1;

    const zwidth::io::ModelFile model = zwidth::io::FittedModelFile(fit, frf, fit_options, argv[1]);
    zwidth::io::WriteModelJson(argv[2], model);
    const double T = frf.period_s();
    for (int d : {1, 2}) {
      const zwidth::stability::DelaySummary s = zwidth::stability::ZWidth(model.plant, T, d).Summarize();
      std::printf("delay %d: K_cr_at_zero_B %.9g K_cr_max %.9g B_max %.9g\n", d, s.K_cr_at_zero_B, s.K_cr_max,
                  s.B_max);
    }
    return fit.quality == zwidth::fit::FitQuality::kGood ? 0 : 1;
  });
}
