// The estimate and the fit of `zwidth run` (and of each unit of `batch`), as
// a RunInput for analysis::Analyse: the logs' response
// (analysis::EstimateFromLogs), the reference's delay in the log's period
// (io::ConvertDelayToPeriod) and its Z-width on a thread of its own while the
// fit runs (FitToModelFile, with the friction fit of FrictionInputFor). The
// CLI and Python's zwidth.run call it.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit_model_file.h"
#include "analysis/logs_estimate.h"
#include "analysis/run.h"

namespace zwidth::analysis {

struct EstimateFitOptions {
  LogsEstimateOptions estimate;  // for the fit (for_fit is set)
  fit::FitOptions fit;
  // With a reference: its Z-width on a thread of its own while the fit runs.
  bool reference_thread = true;
  // FrictionFitOptions::model of the friction fit (FrictionInputFor: one log),
  // as `fit`'s; std::nullopt: friction not looked at.
  std::optional<fit::FrictionModel> friction = fit::FrictionModel::kAuto;
  // ModelFile::linear as the caller gives it (--units, units=); std::nullopt:
  // what the logs' headers say, else rotary (io::LinearUnitsOf, which refuses
  // a header that mixes the two or contradicts the caller).
  std::optional<bool> linear;
};

// What the caller shows as the run goes (each may be empty): the estimate's
// lines (EstimateNote, naming fields), the fit's words and warnings, a note
// ("the reference's delay_samples ... converted"), and each stage's time.
struct RunMessages {
  EstimateNote estimate;
  FitMessages fit;
  std::function<void(const std::string& note)> note;
  std::function<void(const std::string& stage, double ms)> stage;
};

// `in` holds logs, source and the reference (when any); returns it with the
// response, the fit (and the friction fit's result), the model and the
// reference's Z-width. *ms: the time of the two stages. Throws as
// FrictionInputFor (before reading), EstimateFromLogs, io::LinearUnitsOf
// (before the fit; the model's units) and FitToModelFile; a friction not
// checked (several logs, auto) is a messages.fit.warning.
RunInput EstimateAndFit(RunInput in, const EstimateFitOptions& options, const std::vector<int>& delays,
                        const RunMessages& messages = {}, double* ms = nullptr);

// The run's loop for the log's period (a velocity filter's coefficients depend on it).
using LoopForPeriod = std::function<stability::LoopOptions(double period_s)>;

// What `run` computes for one device, below the files: the options checked
// (before anything is read), EstimateAndFit, the loop at the log's period
// (`loop`; options.loop as it is when empty) and Analyse (options.linear: the
// model's, EstimateFitOptions::linear or the headers'). The one pipeline of
// `run` (report::RunToFolder, Python's zwidth.run) and of each unit of
// `batch` (analysis::RunBatch): whether friction is fitted is the one rule of
// EstimateAndFit (EstimateFitOptions::friction, FrictionInputFor). *ms: the
// estimate and fit stages. Throws as IsValid (InputError), EstimateAndFit and Analyse.
RunAnalysis EstimateFitAndAnalyse(RunInput in, const EstimateFitOptions& estimate_fit, RunOptions options,
                                  const LoopForPeriod& loop, const RunMessages& messages = {}, double* ms = nullptr);

}  // namespace zwidth::analysis
