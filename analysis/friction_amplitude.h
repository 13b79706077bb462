// The describing-function amplitude A* along a Z-width's boundary (issue 32,
// stability/friction_prediction.h (b)): at each boundary row (delay, B) with a
// finite K_cr(B) > 0, the wall K = k_factor x K_cr(B) lies outside the linear
// Z-width; Coulomb friction still stops its oscillations below A*. One rule
// for `boundary` (table, CSV, summary JSON) and `run` (summary.json, report):
// both print what FrictionAmplitudes returns. Prints nothing.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/model_json.h"
#include "io/stability_files.h"
#include "model/friction.h"
#include "model/plant.h"
#include "model/units.h"
#include "stability/friction_prediction.h"
#include "stability/loop_options.h"

namespace zwidth::analysis {

struct FrictionAmplitudeOptions {
  double k_factor = 1.25;     // the wall's K as a multiple of K_cr(B) [-], in (1, 100]
  double encoder_step = 0.0;  // rad (or m) per count, >= 0; 0: exact encoder (that validity rule not checked)
  // A* on at most this many rows per delay, evenly spaced in the row order and
  // always the first (B = b_min, usually 0), >= 1; the others stay kNotRun. Each
  // A* costs ~40 exact Z-widths (b_e's bisection): boundary's 1000 B values at
  // 3 delays took 5.8 min on every row (shared 2-core machine, under load).
  int rows_per_delay = 16;
  stability::FrictionPredictionOptions prediction{1e-6};  // A* to ~1e-6 relative
  bool IsValid(std::string* why) const;  // names FrictionAmplitudeOptions::field
};

// The encoder step of the friction predictions: `given` (a caller's
// --encoder-step or keyword; 0: an exact encoder) when given, else the
// model's (io::ModelFile::encoder_step, read from the log it was fitted on),
// else 0. InputError naming `name` when `given` is negative or not finite.
double EncoderStepOf(const io::ModelFile& model, std::optional<double> given,
                     const std::string& name = "FrictionAmplitudeOptions::encoder_step");

struct FrictionAmplitudeRow {
  int delay_samples = 0;
  double B = 0.0;  // N m s/rad
  double K = std::numeric_limits<double>::quiet_NaN();  // k_factor x K_cr(B); nan: no finite K_cr(B) > 0 here
  stability::FrictionPrediction prediction;               // kNotRun where K is nan
};

// One entry per row of `rows` (same order). The friction must have a Coulomb
// level > 0 (InputError naming FrictionAmplitudeOptions otherwise is not
// thrown: with no friction the caller does not call this). Throws InputError
// for invalid options.
std::vector<FrictionAmplitudeRow> FrictionAmplitudes(const model::Plant& plant, double period_s,
                                                     const stability::LoopOptions& loop,
                                                     const std::vector<io::BoundaryRow>& rows,
                                                     const model::Friction& friction,
                                                     const FrictionAmplitudeOptions& options);

// Copies each entry's K, A*, frequency and validity into the BoundaryRow's
// friction columns (rows and amplitudes in the same order).
void SetFrictionColumns(const std::vector<FrictionAmplitudeRow>& amplitudes, std::vector<io::BoundaryRow>* rows);

// One friction prediction (stability::PredictFriction) as JSON, the keys every
// writer uses (boundary's rows and summary, check, wall): "verdict",
// "amplitude" (A* [rad], null = none), "frequency_hz", "extra_damping",
// "K_cr_linear", "valid", "invalid_reason", "rest_point_ok", "K_rest_max".
nlohmann::json FrictionPredictionJson(const stability::FrictionPrediction& p);
// {"B", "K"} and FrictionPredictionJson(r.prediction).
nlohmann::json FrictionAmplitudeRowJson(const FrictionAmplitudeRow& r);
// A summary's "friction" entry for one delay: the Coulomb level used, k_factor,
// encoder_step, K_rest_max (2 F_c / q, null without an encoder step), and
// "at_zero_B": the B = 0 row's FrictionAmplitudeRowJson (null without one).
nlohmann::json FrictionSummaryJson(const std::vector<FrictionAmplitudeRow>& rows, int delay_samples,
                                   const model::Friction& friction, const FrictionAmplitudeOptions& options);
// One line per delay for a terminal or a report, in the model's units: "d = 2
// friction: a wall at 1.25 K_cr(0) = 3.12 N m/rad is stable below A* = 0.109
// rad (7.3 Hz)" (N/m and m for a linear axis).
std::string FrictionSummaryLine(const std::vector<FrictionAmplitudeRow>& rows, int delay_samples,
                                const FrictionAmplitudeOptions& options, const model::UnitLabels& units);

}  // namespace zwidth::analysis
