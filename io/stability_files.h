// Files of the stability commands: the boundary CSV, the summary JSON, and
// haptic scenes {"objects": [{"name": "wall", "K": 20.0, "B": 0.05}, ...]}.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "stability/passivity.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::io {

struct BoundaryRow {
  int delay_samples = 0;
  stability::CriticalPoint point;
  std::vector<stability::KInterval> intervals;  // the stable K intervals at point.B
  double K_cr_std = std::numeric_limits<double>::quiet_NaN();  // N m/rad; nan = no covariance
  // Largest K of the passive set at B (Colgate and Schenkel; stability/passivity.h) [N m/rad]; 0 = none passive.
  double K_passive = std::numeric_limits<double>::quiet_NaN();
  // With friction (analysis/friction_amplitude.h): the wall K = k x K_cr(B)
  // outside the linear Z-width and the amplitude A* below which friction stops
  // its oscillations [rad], at frequency A_star_f_hz; A_star_valid 1/0 = inside
  // / outside the prediction's validity, -1 = not computed (no friction, or a
  // row between the rows_per_delay computed).
  double friction_K = std::numeric_limits<double>::quiet_NaN();
  double A_star = std::numeric_limits<double>::quiet_NaN();
  double A_star_f_hz = std::numeric_limits<double>::quiet_NaN();
  int A_star_valid = -1;
};

// One line per (delay, B, stable interval); a B with no stable K gets one line
// with interval = -1 and K_lo, K_hi = nan. Columns:
//   delay_samples, B                      loop delay [samples], damping [N m s/rad]
//   interval, num_intervals               index of this interval at this B (0 = lowest K), count
//   K_lo, K_hi                            the interval [N m/rad]; K_lo = 0 means from K = 0+, K_hi may be inf
//   f_lo_hz, f_hi_hz                      pole frequency at each end (nan at 0 / inf)
//   interval_verified                     Schur-Cohn agrees at both ends (KInterval::verified)
//   K_cr, K_cr_std, f_cr_hz               the paper's K_CR(B) (K_hi of the interval from 0+, else 0),
//                                         its delta-method std (nan without a covariance), its frequency
//   K_margin, f_margin_hz                 the paper's margin() reading of eq. (4)
//   unstable_at_zero_k, margin_agrees, verified   as in CriticalPoint
//   K_passive                             largest passive K at B (Colgate and Schenkel), 0 = none
//   friction_K, A_star, A_star_f_hz, A_star_valid   only when some row has A_star_valid >= 0 (the
//                                         model has friction): BoundaryRow's friction fields
// The per-B columns from K_cr on repeat on every interval line of that B.
// inf and nan are written as such.
void WriteBoundaryCsv(const std::string& path, const std::vector<BoundaryRow>& rows);

// NaN and inf become null. With std: adds "std": {K_cr_at_zero_B, B_t,
// K_cr_max, B_max} (standard deviations, same units; null = not computed).
nlohmann::json SummaryToJson(const stability::DelaySummary& s,
                             const stability::SummaryStd* std = nullptr);
// [{"K_lo": .., "K_hi": .. (null = +inf), "f_lo_hz", "f_hi_hz", "verified"}]
nlohmann::json IntervalsToJson(const std::vector<stability::KInterval>& intervals);

struct SceneObject {
  std::string name;
  double K = 0.0;  // N m/rad, >= 0
  double B = 0.0;  // N m s/rad, >= 0
};

// The verdict of `zwidth check` for one scene object: stable exactly when K
// lies inside one of the stable K-intervals at its B (K = 0 counts as 0+).
struct ObjectVerdict {
  bool stable = false;
  int interval = -1;          // index of the interval holding K, -1 when unstable
  int nearest_interval = -1;  // the interval nearest to K (-1 when none exists)
  stability::CriticalPoint critical;
  std::vector<stability::KInterval> intervals;
  nlohmann::json ToJson(const SceneObject& o) const;  // the object's entry of `check --json`
};
// Classifies o against the stable intervals at its B (and the K_CR there).
ObjectVerdict Classify(const SceneObject& o, const stability::CriticalPoint& critical,
                       std::vector<stability::KInterval> intervals);
// The same on one loop: Classify(o, z.At(o.B), z.StableIntervals(o.B)).
ObjectVerdict CheckObject(const stability::ZWidth& z, const SceneObject& o);
nlohmann::json NumberOrNull(double v);

// The bounds of a scene (refused beyond them, before the JSON is parsed): at
// most kMaxSceneObjects objects in at most kMaxSceneBytes. `check` costs one
// Z-width evaluation per object and hand: 100000 objects took 10.9 s and 197
// MB (measured on the shared 2-core build machine, under load); a
// 1.2-million-object scene (64 MiB) took 21 s and 2.2 GB.
inline constexpr size_t kMaxSceneObjects = 100000;
// The loop delays a command takes: each in [0, kMaxLoopDelaySamples], at most
// kMaxLoopDelays of them. A delay's Z-width costs time and memory in
// proportion to it (its frequency grid has ~ grid_points_per_delay x d
// points) while the Schur-Cohn test decides, and much more past it: on Table
// I, `boundary --delays 100` took 0.64 s and 150 took 2.7 s, but from about
// 170 samples the polynomial test's error bound fails and the eigenvalue test
// of the (n + d)-state loop decides at every B: 170 took > 25 s, 200 > 120 s
// and 1000 > 7 min (shared 2-core machine, 2026-12-02). This bound does not
// yet bound that work (issue 30).
inline constexpr int kMaxLoopDelaySamples = 1000;
inline constexpr size_t kMaxLoopDelays = 64;
// "" when `delays` keeps those bounds (and is not empty), else the message
// naming `name` (a flag or an options field).
std::string LoopDelaysProblem(const std::vector<int>& delays, const std::string& name);

// Every place that shows a delay gives the loop's (a --delays value: the
// controller's), the fitted model's input delay and their sum, the delay the
// Z-width is computed for: "loop 2 + model 1 = 3 samples".
std::string DelayText(int loop_samples, int model_samples);
// The same in a JSON record: delay_samples (the loop's), model_delay_samples,
// total_delay_samples.
void AddDelays(nlohmann::json* record, int loop_samples, int model_samples);
inline constexpr size_t kMaxSceneBytes = 16u << 20;
std::vector<SceneObject> ReadScene(const std::string& path);
// The scene JSON text's objects, by ReadScene's rules (what `source` names in the
// messages): at least one and at most kMaxSceneObjects, unique non-empty names,
// K and B finite numbers >= 0.
std::vector<SceneObject> ParseScene(const std::string& text, const std::string& source);

// The largest B >= 0 with a passive K >= 0 (Colgate-Schenkel; bisection on
// "the passive set is empty", which grows with B), for physical damping b.
double PassiveBMax(const stability::Passivity& pa, double b);
// The summary's "passivity" object: K_P_at_zero_B, B_P_max, physical_damping_b, meaning.
// A summary's "monte_carlo" entry: {"samples", "seed", "std", "mean"} (boundary --monte-carlo).
nlohmann::json MonteCarloJson(const stability::MonteCarloResult& mc, std::uint64_t seed);
nlohmann::json PassivitySummaryJson(const stability::Passivity& pa, double b);

}  // namespace zwidth::io
