// The fit flags of `fit`, `run` and `batch` (and --friction, --reference) and
// their resolution into the library's options.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "fit/fit.h"
#include "io/model_json.h"

namespace zwidth::flags {

// Parses "auto" or an integer for --delay-samples.
void ResolveDelayFlag(const std::string& flag, fit::FitOptions* o);
// Parses "auto" or an integer for --modes.
void ResolveModesFlag(const std::string& flag, fit::FitOptions* o);

// The fit flags shared by `fit` and `run`: --modes, --max-modes,
// --delay-samples, --max-delay, --allow-short, --min-input-power,
// --min-coherence. Resolve() after parsing: the strings, and the band from
// the Welch flags (--fmin/--fmax also limit a saved response's bins).
struct FitFlags {
  fit::FitOptions o = fit::UserFitOptions();  // the library's defaults of a user's fit
  std::string modes = o.auto_modes ? "auto" : std::to_string(o.num_modes);
  std::string delay = o.auto_delay ? "auto" : std::to_string(o.delay_samples);
  void Resolve(double fmin_hz, double fmax_hz);
};
void AddFitFlags(CLI::App* cmd, FitFlags* flags);

// The verdict, its reasons with advice, the band, the delay and order
// choices, and the stabilisation table, as printed by `fit` and `run`.
std::string FitReport(const fit::FitResult& r);

// --friction none|auto|coulomb (FrictionFitOptions::model), for `fit` and
// `run`; analysis::FrictionModelNamed parses it, analysis::FrictionInputFor
// makes the friction fit's input.
void AddFrictionFlag(CLI::App* cmd, std::string* flag);

// --reference: "table1" (Table I of the paper, built in) or a model JSON path.
// *is_table1 tells which.
io::ModelFile ReadReference(const std::string& flag, bool* is_table1 = nullptr);

}  // namespace zwidth::flags
