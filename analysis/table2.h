// Table II of Gil et al. (the relay experiment on the real PHANToM: K_cr and
// f_cr per delay and B) beside a model's predictions (issue 32):
// - linear: the model's exact Z-width at the point's (delay, B), K_cr(B) and
//   f_cr(B) (stability::ZWidth::At on the paper's loop);
// - friction-aware: the relay experiment simulated on the model with Coulomb
//   friction F_c at the motor and the PHANToM's encoder (stability::SimulateRelay,
//   stick-slip exact), read as the paper read its relay: the spectral peak and
//   |F1| / |X1| there (RelayOptions::refine false); one column per F_c of a grid;
// the F_c whose readings are nearest to the measured K_cr (the error below),
// and how far each prediction is from each point. Nothing is fitted to the
// points but that one level, chosen from the grid. `compare --table2` prints it.
// Prints nothing.
#pragma once

#include <cstddef>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/reference_models.h"
#include "model/plant.h"

namespace zwidth::analysis {

struct Table2Options {
  // The Coulomb levels F_c tried [N m]: each finite and >= 0, 1 to 64 of them.
  std::vector<double> coulomb_levels = {0.0, 0.002, 0.005, 0.01, 0.015, 0.02};
  // The encoder step [rad per count], finite and >= 0: the PHANToM's 40960
  // counts per turn (2 pi / 40960), as `simulate`'s default.
  double encoder_step = 2.0 * std::numbers::pi / 40960.0;
  // The relay's amplitude [N m], > 0: `relay`'s default; the paper does not
  // give its own, and friction's effect scales with F_c / amplitude.
  double relay_amplitude = 0.1;
  // Simulated time of each relay run [s], in [1, 600]; the first half settles.
  double seconds = 10.0;
  bool IsValid(std::string* why) const;  // names Table2Options::field
};

struct Table2Prediction {
  // K_cr [N m/rad]: linear, the exact K_cr(B) (0: unstable as K -> 0+, past
  // B_max_from_zero; inf: no crossing); relay, the peak reading (0: the relay
  // run diverged; NaN: no oscillation).
  double K = std::numeric_limits<double>::quiet_NaN();
  double f_hz = std::numeric_limits<double>::quiet_NaN();  // Hz; NaN when none
  // (K - K_measured) / K_measured and (f - f_measured) / f_measured; NaN when K
  // (or f) is not a finite number > 0.
  double K_rel_error = std::numeric_limits<double>::quiet_NaN();
  double f_rel_error = std::numeric_limits<double>::quiet_NaN();
  // Relay only: RelayResult::unsettled, |L| of the steady part's two halves
  // apart (relative); over 1e-3 the oscillation was still settling and the
  // reading is not a steady one (the text marks it "~"). NaN: linear.
  double unsettled = std::numeric_limits<double>::quiet_NaN();
};

struct Table2Row {
  io::Table2Point point;          // as measured (Table II)
  Table2Prediction linear;        // the model's exact Z-width at (delay, B)
  std::vector<Table2Prediction> relay;  // one per Table2Comparison::coulomb_levels
  // In the error: the linear model has a stable K here (0 < K_cr(B) < inf);
  // the points past the linear B_max (e.g. 3.29 at 188 Hz) are shown, not scored.
  bool scored = false;
};

struct Table2Comparison {
  std::vector<double> coulomb_levels;  // N m, as the options
  double encoder_step = 0.0, relay_amplitude = 0.0, seconds = 0.0;
  std::vector<Table2Row> rows;         // in the order of the points
  int num_scored = 0;
  // The error of a prediction: sqrt(mean over the scored rows of
  // ln(K_predicted / K_measured)^2), a factor (0.1 ~ 10 % off; 2x too high and
  // 2x too low weigh alike); inf when a scored row has no finite K > 0.
  double linear_error = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> relay_error;     // per Coulomb level
  size_t best_level = 0;               // argmin of relay_error (the first of equal ones)
  double best_coulomb() const { return coulomb_levels.at(best_level); }
  int relay_runs = 0;                  // simulated relay runs (one per distinct (delay, B) and level)
};

// The model at period_s (Table II was measured at T = 1 ms: another period is
// an InputError naming it; the points' delays are samples of 1 ms). Throws
// InputError for invalid options or an invalid model. The relay runs go on
// ParallelFor threads; the result does not depend on their number.
Table2Comparison CompareTable2(const model::Plant& plant, double period_s, const std::vector<io::Table2Point>& points,
                               const Table2Options& options = {});

// {"coulomb_levels", "encoder_step", "relay_amplitude", "seconds",
//  "error_meaning", "linear_error", "relay_error", "best_coulomb",
//  "points": [{"delay_samples", "B", "K_cr", "f_cr_hz", "scored",
//              "linear": {K, f_hz, K_rel_error, f_rel_error},
//              "relay": [{"coulomb", K, f_hz, K_rel_error, f_rel_error}, ...]}]}
nlohmann::json Table2Json(const Table2Comparison& c);
// A table for a terminal: per point the measured K at f, the linear and each
// level's relay prediction with its % from the point, then the errors and the
// best level.
std::string Table2Text(const Table2Comparison& c);

}  // namespace zwidth::analysis
