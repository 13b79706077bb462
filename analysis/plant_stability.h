// The Z-width of one fitted model at several delays for one loop, as `zwidth
// run` reports it: summaries with their delta-method std, the boundary rows on
// one B grid (stability/zwidth.h MakeBGrid) with passivity and the std of
// K_CR, all on one sampled plant. Prints nothing.
#pragma once

#include <utility>
#include <vector>

#include "io/model_json.h"
#include "io/stability_files.h"
#include "stability/haptic_loop.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {

struct PlantStability {
  explicit PlantStability(stability::SampledPlant s) : sampled(std::move(s)) {}
  stability::SampledPlant sampled;                  // the model (with the loop's hand), shared by every delay
  std::vector<int> delays;                          // loop delays [samples], in order
  std::vector<stability::ZWidth> zwidths;           // one per delay, sharing one SampledPlant
  std::vector<stability::DelaySummary> summaries;   // one per delay
  std::vector<stability::SummaryStd> stds;          // one per delay; nan without a covariance
  bool has_std = false;                             // the model has a parameter covariance
  std::vector<double> b_grid;                       // B values of the rows [N m s/rad]
  std::vector<io::BoundaryRow> rows;                // [delay][B], delay-major
  int margin_disagreements = 0;                     // rows where margin()'s reading differs
  // What io::ResolveModelPeriod converted: the model's delay_samples counted
  // in samples of period_s when the model was fitted at another period; "".
  std::string period_note;
};

// The model is used at period_s as the CLI's --period uses it
// (io::ResolveModelPeriod): a delay fitted at another period is converted
// when the ratio is whole (period_note says so), else refused (InputError).
// Throws InputError for an invalid period, delay, loop or grid (MakeBGrid's
// messages), after the summaries (the grid's default range comes from them).
PlantStability AnalysePlantStability(const io::ModelFile& model, double period_s, const std::vector<int>& delays,
                                     const stability::LoopOptions& loop, const stability::BGridOptions& grid);

}  // namespace zwidth::analysis
