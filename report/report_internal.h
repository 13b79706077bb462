// Shared by the report's own units; not installed.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "analysis/run.h"
#include "ident/joint.h"

namespace zwidth::report {

// Every figure's canvas [px] (a bound of what any of its panels draws across)
// and how far a thinned line may lie from the computed one on it [px].
inline constexpr double kFigureWidthPx = 900;
inline constexpr double kFigureHeightPx = 640;
inline constexpr double kThinTolerancePx = 0.2;

// What the gnuplot script of `run` depends on.
struct FigureScriptOptions {
  std::vector<int> delays;                // loop delays [samples], one panel/curve each
  int model_delay = 0;                    // the fitted model's input delay [samples], added to each
  ident::CombinedMethod method{};         // the estimate's method (Bode title)
  bool joint = false;                     // closed-loop joint estimate: two coherence columns
  bool linear = false;                    // N s/m and N/m labels instead of N m s/rad, N m/rad
  bool have_ref = false;                  // kcr_reference.dat exists
  bool table1 = false;                    // table2.dat exists
  double k_clip = 1.0;                    // upper K of the region figure [N m/rad]
  double k_clip_loop = 1.0;               // upper K of the loop figure [N m/rad]
  double report_filter_hz = 50.0;         // the loop figure's velocity low-pass [Hz]
  bool png = false;                       // PNGs as well as SVGs
};

// figures.gp: every figure in SVG (and PNG when asked), read from the .dat files beside it.
std::string FigureScript(const FigureScriptOptions& o);

// figures/: the .dat files (figure_files.cc) and figures.gp, whose text it returns.
std::string WriteFigureFiles(const analysis::RunAnalysis& a, const std::filesystem::path& fig, bool png);

// gnuplot started before the run's files are written, so that its start
// (20-25 ms of CPU on the 2-core test machine, nearly all of it the loader
// mapping gnuplot's 82 shared libraries) overlaps the writing; Run() then
// hands it the script. Started like io::RunProgram: an argument vector, no
// shell, in `folder`, its standard error appended to folder/gnuplot.log,
// SIGTERM when this process dies. It reads the script from a pipe as the file
// /dev/stdin, so that an error names its line and ends it, as with a file.
class GnuplotProcess {
 public:
  explicit GnuplotProcess(const std::filesystem::path& folder);
  // Without Run(): the script is empty, gnuplot ends at once and is waited for.
  ~GnuplotProcess();
  GnuplotProcess(const GnuplotProcess&) = delete;
  GnuplotProcess& operator=(const GnuplotProcess&) = delete;
  // Sends the script, closes the pipe and waits: gnuplot's exit status, 127
  // when it could not be started (not installed), 128 + signal when killed.
  int Run(const std::string& script);

 private:
  int Wait();
  pid_t pid_ = -1;     // -1: not started, or waited for
  int to_child_ = -1;  // the pipe's write end
};

// Text as HTML (<, >, & escaped) and the run report's style sheet, shared by
// the fleet report (fleet_report.cc).
std::string HtmlEscaped(const std::string& s);
std::string ReportStyle();

// report.html, one self-contained file; svgs: the drawn figures' SVG text by
// name ("bode", "region", ...), empty when none was drawn; command_line: how
// the run was asked for, shown in its provenance (may be empty).
std::string RunHtml(const analysis::RunAnalysis& a, const std::map<std::string, std::string>& svgs,
                    const std::string& fit_report, const std::string& command_line);

}  // namespace zwidth::report
