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
#include "flags/fit_flags.h"
#include "fit/fit.h"
#include "fit/friction_fit.h"
#include "io/log.h"
#include "io/model_json.h"
#include "stability/zwidth.h"

namespace zwidth::app {

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


}  // namespace zwidth::app
