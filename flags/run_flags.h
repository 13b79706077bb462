// The flags `run` and `batch` share and their options, so that a batch's unit
// is computed exactly as `run` computes that log (one pipeline below:
// analysis::EstimateFitAndAnalyse; flags/run_flags.cc defines these).
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis/run.h"
#include "analysis/run_input.h"
#include "flags/estimate_flags.h"
#include "flags/fit_flags.h"
#include "flags/loop_flags.h"
#include "stability/zwidth.h"

namespace zwidth::flags {

struct RunFlags {
  std::vector<std::string> logs;
  std::string outdir, reference, units;  // units "": the logs' headers', else rotary
  std::string friction = "auto";  // --friction (FrictionFitOptions::model) of run and batch
  std::vector<int> delays = {2, 4, 8};
  EstimateFlags est;
  FitFlags fit;
  stability::BGridOptions grid;
  bool force = false;
  bool no_figures = false;
  bool png = false;
  double report_filter_hz = 50.0;
  LoopFlags loop;
  bool table2 = false;              // run's --table2 (batch has none)
  analysis::Table2Options table2_options;
};

// --reference, --delays, the fit, grid, loop, estimate (log) and --units
// flags: all of run's but the logs, -o, --force, --no-figures, --png, --friction and --table2.
void AddRunAnalysisFlags(CLI::App* cmd, RunFlags* f);

// Flags -> options (the loop comes with the log's period: RunLoop),
// and --reference read into *in; InputError naming the flag, before anything
// is read or written. Resolves f->fit against the Welch band.
analysis::RunOptions ResolveRunOptions(RunFlags* f, analysis::RunInput* in);
// The run's loop for the log's period (one --hand), for `run` and each unit of `batch`.
analysis::LoopForPeriod RunLoop(const RunFlags& f);

}  // namespace zwidth::flags
