// Wiring shared by `fit`, `compare` and `run`.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "analysis/fit_model_file.h"
#include "analysis/table2.h"
#include "apps/common.h"
#include "fit/fit.h"
#include "fit/friction_fit.h"
#include "io/log.h"
#include "io/model_json.h"
#include "stability/zwidth.h"

namespace zwidth::app {

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

using analysis::FrictionInput;  // analysis/fit_model_file.h

// --table2 and its --coulomb-levels, --encoder-step, --amplitude, --seconds
// (analysis::Table2Options), for `compare` and `run`.
void AddTable2Flags(CLI::App* cmd, bool* on, analysis::Table2Options* options);

// "friction: ..." (fitted, or none detected) for `fit` and `run`; "" otherwise (the
// verdict's `friction` reason speaks for a detection that was not fitted).
std::string FrictionLine(const fit::FrictionFitResult& ff);

// analysis::FitToModelFile in the CLI's words (its flags), the fit's warnings
// on stderr.
io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, bool linear, fit::FitResult* result = nullptr,
                             const FrictionInput* friction = nullptr, fit::FrictionFitResult* friction_result = nullptr);

// "parameter value std unit" table; linear: kg and N s/m labels.
std::string ParameterTable(const io::ModelFile& mf, bool linear = false);

// analysis::CompareModels with both models' Z-width computed here (the
// paper's loop). Returns JSON; *text gets the printable version.
nlohmann::json CompareModels(const io::ModelFile& model, const io::ModelFile& reference,
                             const std::vector<int>& delays, double period_s, std::string* text,
                             bool linear = false);

// --reference: "table1" (Table I of the paper, built in) or a model JSON path.
// *is_table1 tells which.
io::ModelFile ReadReference(const std::string& flag, bool* is_table1 = nullptr);

}  // namespace zwidth::app
