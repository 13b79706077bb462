// `zwidth run`'s files from a RunAnalysis: model.json, frf.csv, boundary.csv,
// summary.json, report.html (one self-contained file: the figures inlined) and,
// with figure data, figures/ (the .dat files,
// figures.gp, and the SVG/PNG drawn by gnuplot when it is installed). Writes
// only into the output folder's temporary path; the caller commits it.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "analysis/run.h"
#include "analysis/run_input.h"
#include "io/atomic_file.h"

namespace zwidth::report {

struct RunReportOptions {
  bool draw_figures = true;  // run gnuplot on figures/figures.gp (when the analysis has figure data)
  // figures.gp draws PNGs beside the SVGs (report.html uses the SVGs; the
  // PNGs took about 3/4 of gnuplot's time: 445 of 566 ms on the shipped run).
  bool png = false;
  // The fit's report as the user reads it in report.html (the CLI gives its
  // flags where the library names option fields); analysis::FitReport when empty.
  std::string fit_report;
  // How the run was asked for (the command line, or the Python call), shown
  // in report.html's provenance; may be empty.
  std::string command_line;
};

enum class FiguresStatus {
  kNotRequested,     // the analysis has no figure data: no figures/ folder
  kDrawn,            // gnuplot drew every figure
  kGnuplotMissing,   // gnuplot is not installed: the data and the script are written
  kGnuplotFailed,    // gnuplot exited with an error (see figures/gnuplot.log)
  kNotDrawn,         // draw_figures false: the data and the script are written
};

struct RunReport {
  FiguresStatus figures = FiguresStatus::kNotRequested;
  // "write outputs", "figure files", "figures (gnuplot)" [ms]; gnuplot is
  // started before the outputs are written (it loads meanwhile), so its
  // stage is the time from its script to its exit.
  std::vector<analysis::RunStage> stages;
};

// Throws io's errors when a file cannot be written.
RunReport WriteRunReport(const analysis::RunAnalysis& analysis, const io::OutputFolder& folder,
                         const RunReportOptions& options = {});

// The whole of `zwidth run` below the front ends (the CLI and Python's
// zwidth.run call it): analysis::EstimateFitAndAnalyse (the pipeline each
// unit of `batch` runs too) and WriteRunReport into the folder (the caller
// commits it).
struct RunJob {
  analysis::RunInput input;  // logs, source and the reference (when any)
  analysis::EstimateFitOptions estimate_fit;
  analysis::RunOptions options;
  // The run's loop for the log's period (a velocity filter's coefficients
  // depend on it); options.loop when empty.
  analysis::LoopForPeriod loop;
  RunReportOptions report;  // fit_report: messages.fit.Words(analysis::FitReport) when empty
};

struct RunJobResult {
  analysis::RunAnalysis analysis;
  RunReport report;
  std::string fit_report;         // as report.html shows it
  double estimate_fit_ms = 0.0;   // the estimate and fit stages [ms]
};

// Throws as EstimateAndFit, Analyse and WriteRunReport; nothing is committed.
RunJobResult RunToFolder(RunJob job, const io::OutputFolder& folder, const analysis::RunMessages& messages = {});

}  // namespace zwidth::report
