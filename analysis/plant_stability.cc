#include "analysis/plant_stability.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace zwidth::analysis {

PlantStability AnalysePlantStability(const io::ModelFile& model, double T, const std::vector<int>& delays,
                                     const stability::LoopOptions& loop, const stability::BGridOptions& grid) {
  // One sampled plant (and one set of perturbed plants for the delta method)
  // shared by every delay.
  PlantStability r(stability::SampledPlant(model.plant, T, loop.hand));
  const stability::SampledPlant& sampled = r.sampled;
  r.delays = delays;
  r.has_std = !model.log_covariance.empty();
  r.stds.resize(delays.size());
  std::unique_ptr<stability::PerturbedPlants> perturbed;
  if (r.has_std) {
    stability::CheckLogCovariance(model.plant, model.log_covariance);
    perturbed = std::make_unique<stability::PerturbedPlants>(stability::SamplePerturbedPlants(model.plant, T, loop.hand));
  }
  double b_max = 0.0;
  for (size_t i = 0; i < delays.size(); ++i) {
    r.zwidths.emplace_back(sampled, delays[i], loop);
    r.summaries.push_back(r.zwidths.back().Summarize());
    if (std::isfinite(r.summaries.back().B_max)) b_max = std::max(b_max, r.summaries.back().B_max);
    if (r.has_std) r.stds[i] = stability::SummaryStdDelta(*perturbed, model.log_covariance, delays[i], r.summaries.back(), loop);
  }
  r.b_grid = stability::MakeBGrid(grid, b_max, model.plant.m / T, static_cast<int>(delays.size()));
  const size_t nB = r.b_grid.size();
  r.rows.reserve(delays.size() * nB);
  for (size_t i = 0; i < delays.size(); ++i) {
    const stability::Passivity passivity(model.plant.b, T, r.zwidths[i].total_delay(), loop);  // Colgate-Schenkel
    std::vector<stability::CriticalPoint> pts;
    for (double B : r.b_grid) {
      r.rows.push_back({delays[i], r.zwidths[i].At(B), r.zwidths[i].StableIntervals(B)});
      r.rows.back().K_passive = passivity.At(B).K_hi;
      pts.push_back(r.rows.back().point);
      if (!r.rows.back().point.AgreesWithMargin()) ++r.margin_disagreements;
    }
    if (r.has_std) {
      const std::vector<double> sd = stability::KcrStd(*perturbed, model.log_covariance, delays[i], pts, loop);
      for (size_t k = 0; k < nB; ++k) r.rows[i * nB + k].K_cr_std = sd[k];
    }
  }
  return r;
}

}  // namespace zwidth::analysis
