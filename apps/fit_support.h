// Wiring shared by `fit`, `compare` and `run`.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit/fit.h"
#include "io/model_json.h"
#include "stability/zwidth.h"

namespace zwidth::app {

// Parses "auto" or an integer for --delay-samples.
void ResolveDelayFlag(const std::string& flag, fit::FitOptions* o);

// Fits and packs the model file (std, fit metrics); throws ComputationError
// when the fit does not converge.
io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, fit::FitResult* result = nullptr);

// "parameter value std unit" table; linear: kg and N s/m labels.
std::string ParameterTable(const io::ModelFile& mf, bool linear = false);

// Per-parameter comparison and the stability figures of both models at the
// given delays. Returns JSON; *text gets the printable version. Summaries
// already computed by the caller (one per delay, in order) are reused.
nlohmann::json CompareModels(const io::ModelFile& model, const io::ModelFile& reference,
                             const std::vector<int>& delays, double period_s, std::string* text,
                             const std::vector<stability::DelaySummary>* model_summaries = nullptr,
                             bool linear = false);

// --reference: "table1" (Table I of the paper, built in) or a model JSON path.
// *is_table1 tells which.
io::ModelFile ReadReference(const std::string& flag, bool* is_table1 = nullptr);

}  // namespace zwidth::app
