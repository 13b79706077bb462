#include "analysis/plant_stability.h"

#include "model/parallel.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace zwidth::analysis {
namespace {

// Boundary rows per task: small enough that two threads finish together,
// large enough that a task is worth starting.
constexpr size_t kRowsPerTask = 50;

}  // namespace

PlantStability AnalysePlantStability(const io::ModelFile& fitted, double T, const std::vector<int>& delays,
                                     const stability::LoopOptions& loop, const stability::BGridOptions& grid) {
  io::ModelFile model = fitted;  // its delay counted in samples of T (the CLI's --period rule)
  std::string note;
  io::ResolveModelPeriod(T, &model, &note);
  // One sampled plant (and one set of perturbed plants for the delta method)
  // shared by every delay.
  PlantStability r(stability::SampledPlant(model.plant, T, loop.hand));
  r.period_note = std::move(note);
  const stability::SampledPlant& sampled = r.sampled;
  r.delays = delays;
  r.has_std = !model.log_covariance.empty();
  r.stds.resize(delays.size());
  std::unique_ptr<stability::PerturbedPlants> perturbed;
  if (r.has_std) {
    stability::CheckLogCovariance(model.plant, model.log_covariance);
    perturbed = std::make_unique<stability::PerturbedPlants>(stability::SamplePerturbedPlants(model.plant, T, loop.hand));
  }
  // Every task below writes only its own slots, so the results do not depend
  // on which thread ran what. First the summaries (the B grid's range comes
  // from them) and each delay's passivity condition.
  for (int d : delays) r.zwidths.emplace_back(sampled, d, loop);
  r.summaries.resize(delays.size());
  std::vector<std::unique_ptr<stability::Passivity>> passivity(delays.size());
  ParallelFor(delays.size(), [&](size_t i) {
    r.summaries[i] = r.zwidths[i].Summarize();
    passivity[i] = std::make_unique<stability::Passivity>(model.plant.b, T, r.zwidths[i].total_delay(), loop);  // Colgate-Schenkel
  });
  double b_max = 0.0;
  for (const stability::DelaySummary& s : r.summaries) {
    if (std::isfinite(s.B_max)) b_max = std::max(b_max, s.B_max);
  }
  r.b_grid = stability::MakeBGrid(grid, b_max, model.plant.m / T, static_cast<int>(delays.size()));
  const size_t nB = r.b_grid.size();
  r.rows.resize(delays.size() * nB);
  // Then, as tasks for two threads: each delay's summary std (the largest
  // tasks, first), and the rows in chunks of kRowsPerTask (intervals, K_CR,
  // passivity, std of K_CR: each row depends on its own B only).
  const size_t num_std = r.has_std ? delays.size() : 0;
  const size_t chunks = (nB + kRowsPerTask - 1) / kRowsPerTask;
  std::vector<int> disagreements(delays.size() * chunks, 0);
  ParallelFor(num_std + delays.size() * chunks, [&](size_t task) {
    if (task < num_std) {
      const size_t i = num_std - 1 - task;  // the longest delay first
      r.stds[i] = stability::SummaryStdDelta(*perturbed, model.log_covariance, delays[i], r.summaries[i], loop);
      return;
    }
    const size_t i = (task - num_std) / chunks, c = (task - num_std) % chunks;
    const size_t k0 = c * kRowsPerTask, k1 = std::min(nB, k0 + kRowsPerTask);
    std::vector<stability::CriticalPoint> pts;
    for (size_t k = k0; k < k1; ++k) {
      const double B = r.b_grid[k];
      stability::ZWidth::Row zr = r.zwidths[i].RowAt(B);
      io::BoundaryRow& row = r.rows[i * nB + k];
      row = {delays[i], zr.point, std::move(zr.intervals)};
      row.K_passive = passivity[i]->KHi(B);
      pts.push_back(row.point);
      if (!row.point.AgreesWithMargin()) ++disagreements[i * chunks + c];
    }
    if (r.has_std) {
      const std::vector<double> sd = stability::KcrStd(*perturbed, model.log_covariance, delays[i], pts, loop);
      for (size_t k = k0; k < k1; ++k) r.rows[i * nB + k].K_cr_std = sd[k - k0];
    }
  });
  for (int n : disagreements) r.margin_disagreements += n;
  return r;
}

}  // namespace zwidth::analysis
