#include "analysis/plant_stability.h"

#include "analysis/laps.h"
#include "model/c_locale.h"
#include "model/error.h"
#include "model/parallel.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace zwidth::analysis {
namespace {

// Boundary rows per task: small enough that two threads finish together,
// large enough that a task is worth starting.
constexpr size_t kRowsPerTask = 50;

nlohmann::json LoopJson(const std::vector<stability::LoopOptions>& loops) {
  nlohmann::json j = {{"filter_b", loops[0].filter_b}, {"filter_a", loops[0].filter_a},
                      {"hands", nlohmann::json::array()}};
  for (const auto& l : loops) {
    if (!l.hand.IsNone()) j["hands"].push_back({{"M", l.hand.M}, {"B", l.hand.B}, {"K", l.hand.K}});
  }
  return j;
}

}  // namespace

bool PlantStabilityOptions::IsValid(std::string* why) const {
  // The first problem, in the order of the fields; "" when none.
  std::string p = io::LoopDelaysProblem(delays, "PlantStabilityOptions::delays"), w;
  if (p.empty() && loops.empty()) p = "PlantStabilityOptions::loops is empty: give at least one loop";
  for (size_t h = 0; h < loops.size() && p.empty(); ++h) {
    if (!loops[h].IsValid(&w)) p = "PlantStabilityOptions::loops[" + std::to_string(h) + "]." + w;
  }
  if (p.empty() && !grid.IsValid(&w)) p = w;
  // A hand's, a wall's and a scene's B bound (stability::kMaxLoopValue): --b-max 1e300 gave rows up to 1e300.
  if (p.empty() && grid.b_max > stability::kMaxLoopValue) {
    p = "BGridOptions::b_max = " + FormatG(grid.b_max) + " is above 1e12 (N m s/rad; N s/m on a linear axis)";
  }
  if (p.empty() && monte_carlo < 0) p = "PlantStabilityOptions::monte_carlo must be >= 0";
  if (p.empty() && monte_carlo > 0 && loops.size() > 1) {
    p = "PlantStabilityOptions::monte_carlo takes at most one PlantStabilityOptions::loops";
  }
  if (p.empty() && !amplitude.IsValid(&w)) p = w;
  if (!p.empty() && why) *why = p;
  return p.empty();
}

PlantStability AnalysePlantStability(const io::ModelFile& fitted, double T, const PlantStabilityOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  if (o.monte_carlo > 0 && fitted.log_covariance.empty()) {
    throw InputError("PlantStabilityOptions::monte_carlo needs a model with a \"covariance\" (a model written by "
                     "zwidth fit)");
  }
  io::ModelFile model = fitted;  // its delay counted in samples of T (the CLI's --period rule)
  std::string note;
  io::ResolveModelPeriod(T, &model, &note);
  const std::vector<int>& delays = o.delays;
  const std::vector<stability::LoopOptions>& loops = o.loops;
  const stability::LoopOptions& loop = loops[0];
  const size_t nd = delays.size(), nl = loops.size();
  // One sampled plant per loop (and one set of perturbed plants for the
  // delta method) shared by every delay.
  PlantStability r(stability::SampledPlant(model.plant, T, loop.hand));
  r.period_note = std::move(note);
  r.delays = delays;
  r.loops = loops;
  std::vector<stability::SampledPlant> other_sampled;  // loops 1..
  for (size_t h = 1; h < nl; ++h) other_sampled.emplace_back(model.plant, T, loops[h].hand);
  // The delta method and Monte Carlo for one loop (with its filter and hand).
  r.has_std = !model.log_covariance.empty() && nl == 1;
  r.stds.resize(nd);
  std::unique_ptr<stability::PerturbedPlants> perturbed;
  if (r.has_std) {
    stability::CheckLogCovariance(model.plant, model.log_covariance);
    perturbed = std::make_unique<stability::PerturbedPlants>(stability::SamplePerturbedPlants(model.plant, T, loop.hand));
  }
  // Every task below writes only its own slots, so the results do not depend
  // on which thread ran what. First the summaries of every loop (the B grid's
  // range comes from them) and each delay's passivity condition.
  std::vector<std::vector<stability::ZWidth>> other_z(nd);  // [delay][loop - 1]
  for (size_t i = 0; i < nd; ++i) {
    r.zwidths.emplace_back(r.sampled, delays[i], loop);
    for (size_t h = 1; h < nl; ++h) other_z[i].emplace_back(other_sampled[h - 1], delays[i], loops[h]);
  }
  std::vector<std::vector<stability::DelaySummary>> sums(nd, std::vector<stability::DelaySummary>(nl));
  std::vector<std::unique_ptr<stability::Passivity>> passivity(nd);
  ParallelFor(nd * nl, [&](size_t task) {
    const size_t i = task / nl, h = task % nl;
    sums[i][h] = h == 0 ? r.zwidths[i].Summarize() : other_z[i][h - 1].Summarize();
    if (h == 0) {
      passivity[i] = std::make_unique<stability::Passivity>(model.plant.b, T, r.zwidths[i].total_delay(), loop);
    }
  });
  double b_max = 0.0;
  for (size_t i = 0; i < nd; ++i) {
    r.summaries.push_back(sums[i][0]);
    r.passivity.push_back(std::move(*passivity[i]));
    for (const stability::DelaySummary& s : sums[i]) {
      if (std::isfinite(s.B_max)) b_max = std::max(b_max, s.B_max);
    }
  }
  if (nl > 1) r.loop_summaries = std::move(sums);
  r.b_grid = stability::MakeBGrid(o.grid, b_max, model.plant.m / T, static_cast<int>(nd));
  const size_t nB = r.b_grid.size();
  r.rows.resize(nd * nB);
  // Then, as tasks for two threads: each delay's summary std (the largest
  // tasks, first), and the rows in chunks of kRowsPerTask (intervals, K_CR,
  // passivity, std of K_CR: each row depends on its own B only).
  const size_t num_std = r.has_std ? nd : 0;
  const size_t chunks = (nB + kRowsPerTask - 1) / kRowsPerTask;
  std::vector<int> disagreements(nd * chunks, 0);
  ParallelFor(num_std + nd * chunks, [&](size_t task) {
    if (task < num_std) {
      const size_t i = num_std - 1 - task;  // the longest delay first
      r.stds[i] = stability::SummaryStdDelta(r.zwidths[i], *perturbed, model.log_covariance, delays[i], r.summaries[i]);
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
      for (const stability::ZWidth& z : other_z[i]) {  // the region stable for every loop
        row.intervals = stability::IntersectIntervals(row.intervals, z.StableIntervals(B));
        const stability::CriticalPoint cp = z.At(B);
        if (cp.K_cr < row.point.K_cr) row.point = cp;
      }
      row.K_passive = r.passivity[i].KHi(B);
      pts.push_back(row.point);
      if (!row.point.AgreesWithMargin()) ++disagreements[i * chunks + c];
    }
    if (r.has_std) {
      const std::vector<double> sd = stability::KcrStd(*perturbed, model.log_covariance, delays[i], pts, loop);
      for (size_t k = k0; k < k1; ++k) r.rows[i * nB + k].K_cr_std = sd[k - k0];
    }
  });
  for (int n : disagreements) r.margin_disagreements += n;
  for (size_t i = 0; i < nd && o.monte_carlo > 0; ++i) {
    if (o.on_monte_carlo) o.on_monte_carlo(delays[i], o.monte_carlo);
    r.monte_carlo_seed = o.seed;
    r.monte_carlo.push_back(
        stability::SummaryMonteCarlo(model.plant, model.log_covariance, T, delays[i], o.monte_carlo, o.seed, loop));
  }
  // With friction: A* at k x K_cr(B) on the rows (the first loop).
  if (o.friction && o.friction->MeanCoulomb() > 0.0) {
    Laps laps;
    r.friction = *o.friction;
    r.friction_options = o.amplitude;
    r.friction_amplitudes = FrictionAmplitudes(model.plant, T, loop, r.rows, r.friction, r.friction_options);
    SetFrictionColumns(r.friction_amplitudes, &r.rows);
    r.friction_amplitude_ms = laps.Lap();
  }
  return r;
}

nlohmann::json DelaySummaryJson(const stability::DelaySummary& summary, const stability::SummaryStd* std_or_null,
                                int delay_samples, const model::Plant& plant, const stability::Passivity& passivity,
                                const stability::MonteCarloResult* monte_carlo_or_null, std::uint64_t seed) {
  nlohmann::json e = io::SummaryToJson(summary, std_or_null);
  io::AddDelays(&e, delay_samples, plant.delay_samples);
  e["passivity"] = io::PassivitySummaryJson(passivity, plant.b);
  if (monte_carlo_or_null) e["monte_carlo"] = io::MonteCarloJson(*monte_carlo_or_null, seed);
  return e;
}

nlohmann::json PlantStabilityJson(const PlantStability& st) {
  const model::Plant& plant = st.sampled.plant();
  nlohmann::json js;
  js["period_s"] = st.sampled.period_s();
  js["model"] = plant.name;
  js["B_max_meaning"] = "B_max: the largest B at which some K > 0 is stable (reopened bands included); "
                        "B_max_from_zero: the B where the interval from K = 0+ closes (the paper's B_max)";
  js["delays"] = nlohmann::json::array();
  for (size_t i = 0; i < st.delays.size(); ++i) {
    nlohmann::json e = DelaySummaryJson(st.summaries[i], st.has_std ? &st.stds[i] : nullptr, st.delays[i], plant,
                                        st.passivity[i], st.monte_carlo.empty() ? nullptr : &st.monte_carlo[i],
                                        st.monte_carlo_seed);
    if (!st.loop_summaries.empty()) {
      e["per_hand"] = nlohmann::json::array();
      for (size_t h = 0; h < st.loops.size(); ++h) {
        nlohmann::json eh = io::SummaryToJson(st.loop_summaries[i][h]);
        const auto& hand = st.loops[h].hand;
        eh["hand"] = {{"M", hand.M}, {"B", hand.B}, {"K", hand.K}};
        e["per_hand"].push_back(eh);
      }
    }
    if (!st.friction_amplitudes.empty()) {
      e["friction"] = FrictionSummaryJson(st.friction_amplitudes, st.delays[i], st.friction, st.friction_options);
    }
    js["delays"].push_back(e);
  }
  js["margin_disagreements"] = st.margin_disagreements;
  js["loop"] = LoopJson(st.loops);
  return js;
}

}  // namespace zwidth::analysis
