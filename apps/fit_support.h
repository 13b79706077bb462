// Wiring shared by `fit`, `compare` and `run`.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "fit/fit.h"
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
  std::string modes = "2", delay = "0";
  fit::FitOptions o;
  void Resolve(double fmin_hz, double fmax_hz);
};
void AddFitFlags(CLI::App* cmd, FitFlags* flags);

// The verdict, its reasons with advice, the band, the delay and order
// choices, and the stabilisation table, as printed by `fit` and `run`.
std::string FitReport(const fit::FitResult& r);

// Fits and packs the model file (std, fit metrics); throws ComputationError
// when the fit does not converge.
io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, fit::FitResult* result = nullptr);

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
