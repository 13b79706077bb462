#include "analysis/plant_stability.h"

#include "model/parallel.h"

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
  // The delays are independent: each one's summary, std and rows are
  // computed on its own thread and written to its own slots.
  for (int d : delays) r.zwidths.emplace_back(sampled, d, loop);
  r.summaries.resize(delays.size());
  ParallelFor(delays.size(), [&](size_t i) {
    r.summaries[i] = r.zwidths[i].Summarize();
    if (r.has_std) r.stds[i] = stability::SummaryStdDelta(*perturbed, model.log_covariance, delays[i], r.summaries[i], loop);
  });
  double b_max = 0.0;
  for (const stability::DelaySummary& s : r.summaries) {
    if (std::isfinite(s.B_max)) b_max = std::max(b_max, s.B_max);
  }
  r.b_grid = stability::MakeBGrid(grid, b_max, model.plant.m / T, static_cast<int>(delays.size()));
  const size_t nB = r.b_grid.size();
  r.rows.resize(delays.size() * nB);
  std::vector<int> disagreements(delays.size(), 0);
  ParallelFor(delays.size(), [&](size_t i) {
    const stability::Passivity passivity(model.plant.b, T, r.zwidths[i].total_delay(), loop);  // Colgate-Schenkel
    std::vector<stability::CriticalPoint> pts;
    for (size_t k = 0; k < nB; ++k) {
      const double B = r.b_grid[k];
      io::BoundaryRow& row = r.rows[i * nB + k];
      row = {delays[i], r.zwidths[i].At(B), r.zwidths[i].StableIntervals(B)};
      row.K_passive = passivity.At(B).K_hi;
      pts.push_back(row.point);
      if (!row.point.AgreesWithMargin()) ++disagreements[i];
    }
    if (r.has_std) {
      const std::vector<double> sd = stability::KcrStd(*perturbed, model.log_covariance, delays[i], pts, loop);
      for (size_t k = 0; k < nB; ++k) r.rows[i * nB + k].K_cr_std = sd[k];
    }
  });
  for (int n : disagreements) r.margin_disagreements += n;
  return r;
}

}  // namespace zwidth::analysis
