// A fitted model beside a reference: per-parameter differences and what they do
// to the Z-width (the paper's loop), as JSON and as a printable table. Prints
// nothing.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/model_json.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {

// "param value std unit" table of a model (std from its std_errors, inf when
// none); linear: kg and N s/m labels instead of kg m^2 and N m s/rad.
std::string ParameterTable(const io::ModelFile& mf, bool linear = false);

// The Z-width summaries of one model at several delays (the loop it was
// computed for), with the delta-method std when has_std.
struct DelayStability {
  std::vector<stability::DelaySummary> summaries;  // one per delay, in order
  std::vector<stability::SummaryStd> stds;         // one per delay; nan where not computed
  bool has_std = false;                            // the model had a parameter covariance
};
// The paper's loop (no filter, no hand) at each delay, on one sampled plant.
DelayStability SummarizeDelays(const io::ModelFile& mf, double period_s, const std::vector<int>& delays);

// A comparison of a rotary model with a linear one compares kg m^2 with kg:
// InputError naming both (model_name, reference_name), their units and what
// to do. model_linear: the model's units as the caller reads them.
void CheckSameUnits(bool model_linear, const io::ModelFile& reference, const std::string& model_name,
                    const std::string& reference_name);

struct ModelComparison {
  nlohmann::json json;  // {"parameters": [...], "stability": [...]}
  std::string text;     // the same as a printable table
};
// model_stability and reference_summaries: the paper's loop at `delays`, in
// order (model_stability.summaries.size() == delays.size()). Refuses models
// of different units (CheckSameUnits; linear || model.linear is the model's).
ModelComparison CompareModels(const io::ModelFile& model, const io::ModelFile& reference,
                              const std::vector<int>& delays, const DelayStability& model_stability,
                              const std::vector<stability::DelaySummary>& reference_summaries,
                              bool linear = false);

}  // namespace zwidth::analysis
