// The Z-width of one model at several delays, as `zwidth run` and `zwidth
// boundary` report it (one function for both, issue 24): the model at its
// period, one loop per hand, the summaries per delay with their delta-method
// std (and Monte Carlo), passivity, the boundary rows on one B grid
// (stability/zwidth.h MakeBGrid) with the std of K_CR, and with friction the
// amplitude A* along them, all on one sampled plant per hand. Prints nothing.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/friction_amplitude.h"
#include "io/model_json.h"
#include "io/stability_files.h"
#include "model/friction.h"
#include "stability/loop_options.h"
#include "stability/passivity.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {

struct PlantStabilityOptions {
  std::vector<int> delays = {2, 4, 8};  // loop delays [samples], in order (io::LoopDelaysProblem's range)
  // One loop per hand of the user (each with the same velocity filter), at
  // least one. The first is the reported loop: its summaries, passivity, std,
  // Monte Carlo and friction amplitudes. With several, the rows hold the
  // region stable for every loop (intervals intersected, the lowest K_CR) and
  // no std is computed.
  std::vector<stability::LoopOptions> loops = {stability::LoopOptions{}};
  stability::BGridOptions grid;  // B grid of the rows
  // Draws of the parameter covariance per delay for the Monte Carlo std
  // beside the delta method's (stability::SummaryMonteCarlo), >= 0; 0: off.
  // Needs a model with a covariance and one loop.
  int monte_carlo = 0;
  std::uint64_t seed = 1;  // of the Monte Carlo draws
  // Coulomb friction: with a level > 0, A* on the rows (FrictionAmplitudes
  // on the first loop, into the rows' friction columns); none: not computed.
  std::optional<model::Friction> friction;
  FrictionAmplitudeOptions amplitude;
  // Called before each delay's Monte Carlo (delay [samples], draws), for a
  // progress line; may be empty.
  std::function<void(int delay, int samples)> on_monte_carlo;
  // False with *why naming PlantStabilityOptions::field (or the grid's or
  // amplitude's field) when a field is out of range.
  bool IsValid(std::string* why) const;
};

struct PlantStability {
  explicit PlantStability(stability::SampledPlant s) : sampled(std::move(s)) {}
  stability::SampledPlant sampled;                  // the model at its period with the first loop's hand
  std::vector<int> delays;                          // loop delays [samples], in order
  std::vector<stability::LoopOptions> loops;        // as PlantStabilityOptions::loops
  std::vector<stability::ZWidth> zwidths;           // one per delay (first loop), sharing one SampledPlant
  std::vector<stability::DelaySummary> summaries;   // one per delay (first loop)
  // [delay][loop] with several loops (the first equal to summaries); else empty.
  std::vector<std::vector<stability::DelaySummary>> loop_summaries;
  std::vector<stability::Passivity> passivity;      // one per delay (first loop; Colgate-Schenkel)
  std::vector<stability::SummaryStd> stds;          // one per delay; nan without a covariance
  bool has_std = false;                             // a covariance and one loop
  std::vector<stability::MonteCarloResult> monte_carlo;  // one per delay with PlantStabilityOptions::monte_carlo
  std::uint64_t monte_carlo_seed = 1;               // their seed
  std::vector<double> b_grid;                       // B values of the rows [N m s/rad]
  std::vector<io::BoundaryRow> rows;                // [delay][B], delay-major
  int margin_disagreements = 0;                     // rows where margin()'s reading differs
  // With friction (PlantStabilityOptions::friction, a level > 0): one per row
  // (same order), also in the rows' friction columns; else empty.
  std::vector<FrictionAmplitudeRow> friction_amplitudes;
  model::Friction friction;                         // the friction used for them
  FrictionAmplitudeOptions friction_options;        // the options used for them
  double friction_amplitude_ms = 0.0;               // their wall time [ms]; 0 when not computed
  // What io::ResolveModelPeriod converted: the model's delay_samples counted
  // in samples of period_s when the model was fitted at another period; "".
  std::string period_note;
};

// The model is used at period_s as the CLI's --period uses it
// (io::ResolveModelPeriod): a delay fitted at another period is converted
// when the ratio is whole (period_note says so), else refused (InputError).
// Throws InputError for invalid options (PlantStabilityOptions::IsValid),
// for a Monte Carlo without a covariance, an invalid period, delay, loop or
// grid (MakeBGrid's messages, after the summaries: the grid's default range
// comes from them).
PlantStability AnalysePlantStability(const io::ModelFile& model, double period_s, const PlantStabilityOptions& options);

// One entry of a summary JSON's "delays": io::SummaryToJson (with the std
// when given), the loop, model and total delays (io::AddDelays), "passivity"
// and, when given, "monte_carlo" (with its seed). `boundary --summary` and
// Python's ZWidth.summary write this.
nlohmann::json DelaySummaryJson(const stability::DelaySummary& summary, const stability::SummaryStd* std_or_null,
                                int delay_samples, const model::Plant& plant, const stability::Passivity& passivity,
                                const stability::MonteCarloResult* monte_carlo_or_null, std::uint64_t seed);

// `boundary --summary`'s JSON without its provenance: period_s, model,
// B_max_meaning, "delays" (DelaySummaryJson per delay, with "per_hand" with
// several loops and "friction" with friction amplitudes), margin_disagreements
// and "loop" (the velocity filter and the hands).
nlohmann::json PlantStabilityJson(const PlantStability& stability);

}  // namespace zwidth::analysis
