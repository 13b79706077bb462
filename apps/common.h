// Options shared by several subcommands, and the one place that maps errors to
// exit codes (2: bad request or file, 1: a computation that failed).
#pragma once

#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis/logs_estimate.h"
#include "ident/joint.h"
#include "ident/local_models.h"
#include "ident/welch.h"
#include "io/log.h"
#include "io/model_json.h"
#include "flags/estimate_flags.h"
#include "flags/flag_guard.h"

#include <limits>

namespace zwidth::app {

// The flags shared with zwidth.batch (flags/: the option table below apps).
using namespace zwidth::flags;

// The library's messages name option fields ("WelchOptions::window_length");
// the CLI's name flags: the message with each field replaced by its flag
// (io::WithFlags; the one table of fields, flags and keywords is io/option_names.cc).
std::string WithFlags(const std::string& message);

// The command line as typed (main stores it), each argument quoted for a
// POSIX shell where it needs it: the provenance of report.html.
void SetCommandLine(int argc, char** argv);
const std::string& CommandLine();


using analysis::LogsEstimate;
// Reads the logs (runs of one device) and combines their spectra
// (analysis::EstimateFromLogs). Prints how each log was read, its warnings and
// samples left out of the segments. for_fit: a whole record of one segment
// (no per-bin std to weight a fit) is refused rather than warned about.
LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const EstimateFlags& flags,
                              bool for_fit = false);
std::string JoinPaths(const std::vector<std::string>& paths);

// --seed: a whole number in [0, 2^64 - 1]; "-1" is refused (CLI11 would wrap
// it to 2^64 - 1 silently).
CLI::Option* AddSeedOption(CLI::App* cmd, std::uint64_t* seed, const std::string& help);

// Prints "stage: 1.23 ms" to stderr.
class StageTimer {
 public:
  explicit StageTimer(bool enabled = true) : enabled_(enabled) { Reset(); }
  void Reset() { start_ = std::chrono::steady_clock::now(); }
  double Lap(const std::string& stage);  // returns ms since last lap and prints it
 private:
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

// Flags whose absence means "use the model's value".
inline constexpr double kNotGiven = std::numeric_limits<double>::quiet_NaN();
inline std::optional<double> Given(double flag) { return std::isnan(flag) ? std::nullopt : std::optional(flag); }
// --encoder-step of the commands that read a model (analysis::EncoderStepOf).
inline constexpr const char* kEncoderStepHelp =
    "rad (m on a linear axis) per encoder count (default: the model's encoder_step, read from the log it was fitted "
    "on, else 0; 0: exact)";
// --period when given, else the model's sample_period_s, else 1 ms. A given
// --period must lie in [io::kMinPeriodS, io::kMaxPeriodS] (the rates a log may
// have, 10 Hz..1 MHz; the same rule as a model's sample_period_s). When T
// differs from the model's sample_period_s the model's delay_samples (counted
// in its own period) is converted to samples of T (ConvertDelayToPeriod).
double ResolvePeriod(double flag, io::ModelFile* mf);
// delay_samples of a model with sample_period_s T_m, counted in samples of T:
// d T_m / T when that is a whole number (to 1e-9; a note on stderr says so),
// else an InputError saying why and what to do. `what` names the model.
void ConvertDelayToPeriod(io::ModelFile* mf, double T, const std::string& what);

// Thrown by a subcommand to end with a documented exit status other than 0
// (check: 3 when an object is unstable) once its output is complete.
struct ExitStatus {
  int code;
};
// %g of v, for messages.
std::string Num(double v);

void AddSimulateCommand(CLI::App& app);
void AddEstimateCommand(CLI::App& app);
void AddFitCommands(CLI::App& app);        // fit, compare
void AddStabilityCommands(CLI::App& app);  // boundary, relay, check
void AddExportCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddBatchCommand(CLI::App& app);
void AddExciteCommand(CLI::App& app);
void AddValidateCommand(CLI::App& app);    // validate a model on a fresh log
void AddWallCommand(CLI::App& app);

}  // namespace zwidth::app
