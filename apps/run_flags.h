// The flags `run` and `batch` share, and the estimate and fit of one run, so
// that a batch's unit is computed exactly as `run` computes that log
// (apps/cmd_run.cc defines them).
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis/run.h"
#include "apps/common.h"
#include "apps/fit_support.h"
#include "apps/loop_flags.h"

namespace zwidth::app {

struct RunFlags {
  std::vector<std::string> logs;
  std::string outdir, reference, units = "rotary";
  std::string friction = "auto";  // run's --friction (FrictionFitOptions::model); batch fits no friction
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
// flags: all of run's but the logs, -o, --force, --no-figures, --png and --friction.
void AddRunAnalysisFlags(CLI::App* cmd, RunFlags* f);

// Flags -> options (the loop comes with the log's period: ResolveRunLoop),
// and --reference read into *in; InputError naming the flag, before anything
// is read or written. Resolves f->fit against the Welch band.
analysis::RunOptions ResolveRunOptions(RunFlags* f, analysis::RunInput* in);
// The run's loop for the log's period (one --hand).
void ResolveRunLoop(const RunFlags& f, double period_s, analysis::RunOptions* o);

// The estimate and the linear fit of a batch unit (timed into *t_total_ms,
// printed unless MessagesQuiet()), as analysis::RunInput: friction is not
// looked at (EstimateFitOptions::friction std::nullopt): the units run on
// threads, and the CLI's fit plugin plans FFTs under a lock of its own
// (zwidth::FftwPlannerMutex). With reference_thread and a reference, its
// Z-width is computed on a thread of its own while the fit runs.
analysis::RunInput EstimateAndFit(const RunFlags& f, const analysis::RunOptions& o, analysis::RunInput in,
                                  double* t_total_ms, bool reference_thread = true);

}  // namespace zwidth::app
