// Options shared by several subcommands, and the one place that maps errors to
// exit codes (2: bad request or file, 1: a computation that failed).
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis/logs_estimate.h"
#include "ident/joint.h"
#include "ident/local_models.h"
#include "ident/welch.h"
#include "io/log.h"
#include "io/model_json.h"

#include <limits>

namespace zwidth::app {

// The library's messages name option fields ("WelchOptions::window_length");
// the CLI's name flags: the message with each field replaced by its flag
// (io::WithFlags; the one table of fields, flags and keywords is io/option_names.cc).
std::string WithFlags(const std::string& message);

// The command line as typed (main stores it), each argument quoted for a
// POSIX shell where it needs it: the provenance of report.html.
void SetCommandLine(int argc, char** argv);
const std::string& CommandLine();

struct EstimateFlags {
  io::LogSelect select;
  // window_length 0 (the default): ident::DefaultWindowLength of the first
  // log's rate and length, resolved when the log is read.
  ident::WelchOptions welch{.window_length = 0};
  std::string window = "hann", estimator = "h1";
  // none | mean | linear; "" = not given: linear, or mean with whole_record
  // (a per-segment linear detrend of a rectangular one-period segment leaks
  // the slow response's straight-line fit into every bin).
  std::string detrend;
  // Closed loop: the logged excitation (text/.mat column, HDF5 dataset); when
  // given, H = S_ry / S_ru (ident/joint.h).
  std::string reference_column, reference_dataset;
  // Each run one rectangular segment; per-bin std from the scatter between runs.
  bool whole_record = false;
  // With whole_record: one segment per period of this many samples (a
  // periodic excitation's period) instead of one per log; 0 = the whole log.
  int period_samples = 0;
  // --estimator lpm|lrm: the local methods' options (ident/local_models.h);
  // the band comes from welch.fmin_hz/fmax_hz.
  ident::LocalModelOptions local;
  bool IsLocal() const { return estimator == "lpm" || estimator == "lrm"; }
  // --estimator robust: the robust method of a periodic excitation
  // (ident/robust_frf.h), period_samples per period, each log a realisation.
  bool IsRobust() const { return estimator == "robust"; }
  int transient_periods = ident::RobustOptions{}.transient_periods;
  // Parses the enum names; throws InputError naming the flag.
  ident::WelchOptions Resolve() const;
  ident::LocalModelOptions ResolveLocal() const;  // with IsLocal()
  std::string ResolvedDetrend() const;  // detrend, or its default when not given
  // The library's options (throws InputError naming the flag).
  analysis::LogsEstimateOptions Options(bool for_fit) const;
};

void AddLogFlags(CLI::App* cmd, io::LogSelect* select);
void AddEstimateFlags(CLI::App* cmd, EstimateFlags* flags);

using analysis::LogsEstimate;
// Reads the logs (runs of one device) and combines their spectra
// (analysis::EstimateFromLogs). Prints how each log was read, its warnings and
// samples left out of the segments. for_fit: a whole record of one segment
// (no per-bin std to weight a fit) is refused rather than warned about.
LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const EstimateFlags& flags,
                              bool for_fit = false);
std::string JoinPaths(const std::vector<std::string>& paths);

// --units rotary|linear: parameter labels (kg m^2, N m s/rad | kg, N s/m).
void AddUnitsFlag(CLI::App* cmd, std::string* units);
// --seed: a whole number in [0, 2^64 - 1]; "-1" is refused (CLI11 would wrap
// it to 2^64 - 1 silently).
CLI::Option* AddSeedOption(CLI::App* cmd, std::uint64_t* seed, const std::string& help);
bool LinearUnits(const std::string& units);  // throws InputError for another word

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

// Adds to every numeric option of `app` and its subcommands (after they are
// declared) the one check of a typed number: an empty value, NaN or an
// infinity is refused naming the flag (exit 2), as are non-numbers.
void GuardNumericFlags(CLI::App* app);
// CLI11 drops the empty items of a delimited list (`--delays 2,,4` read as
// 2,4) before any check sees them, so the command line itself is read first:
// an empty item in the value of any option of `app` (or its subcommands) that
// has a delimiter is an InputError naming the flag and the item.
void CheckListFlags(const CLI::App& app, int argc, char** argv);

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
