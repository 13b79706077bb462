// What Coulomb friction and the encoder do to a wall's stability (issue 32),
// as three labelled predictions beside the linear Z-width:
//
// (a) Linear: (K, B) inside the Z-width of the linear part (friction removed)
//     is stable for any disturbance: friction's equivalent damping vanishes at
//     large amplitude, so only the linear part decides there.
// (b) Amplitude: outside it, friction still stops oscillations below
//       A* = 4 F_c / (pi omega b_e),
//     from the describing function of Coulomb friction (its fundamental is a
//     viscous damping 4 F_c / (pi omega A) at velocity amplitude omega A).
//     b_e is the extra physical damping that makes (K, B) marginally stable,
//     omega the loop's crossing frequency there. The extra damping acts where
//     the friction does (the plant input, velocity of the measured coordinate):
//     exactly the hand's damping of stability/hand.h, so b_e is a 1-D
//     root of "K is stable at B" in the hand's B_h, each test an exact Z-width
//     (SampledPlant + ZWidth). Without modes this is the brief's b* - b.
//     A* is an unstable limit cycle: a start below it dies out, above it grows.
// (c) Encoder: the rest-point condition of Abbott and Okamura (2005): a wall
//     of stiffness K on an encoder of step q can hold the device still at a
//     quantised position when K q <= 2 F_c (friction spans the force jump of
//     one count); past it the wall can buzz between counts.
//
// Where (b) holds (checked and reported in `valid`, `invalid_reason`):
//   - A* >= 10 encoder steps (else quantisation, not friction, sets the motion;
//     set from the random-case test: 6.8 steps gave +18 %);
//   - K A* >= 3 x the static level (the wall's force at the turning points
//     breaks the body loose: the describing function assumes it slides the
//     whole cycle; below it the body sticks at a turning point and stops);
//   - one crossing near K at b_e (no second crossing within 10 % of K, a
//     single dominant oscillation);
//   - the friction is the describing function's: the mean Coulomb level of an
//     asymmetric friction is used, the offset is ignored.
#pragma once

#include <limits>
#include <string>

#include "model/friction.h"
#include "model/plant.h"
#include "stability/loop_options.h"

namespace zwidth::stability {

enum class FrictionVerdict {
  kNotRun,
  kLinearStable,     // (a): stable for any disturbance
  kStableBelow,      // (b): stable for oscillations below `amplitude`
  kUnstable,         // no friction (F_c = 0), or no extra damping up to the search bound stabilises it
};
std::string ToString(FrictionVerdict v);  // "linear_stable", "stable_below_amplitude", "unstable", "not_run"

struct FrictionPredictionOptions {
  double relative_tolerance = 1e-9;  // of b_e's bisection, in (0, 0.1)
  double max_extra_damping_factor = 1e6;  // b_e searched up to this x (b + B + 1e-9) [-], > 1
  bool IsValid(std::string* why) const;
};

struct FrictionPrediction {
  FrictionVerdict verdict = FrictionVerdict::kNotRun;
  double K_cr_linear = std::numeric_limits<double>::quiet_NaN();  // K_cr(B) of the linear part [N m/rad]
  double extra_damping = std::numeric_limits<double>::quiet_NaN();  // b_e [N m s/rad]
  double frequency_hz = std::numeric_limits<double>::quiet_NaN();   // omega / 2 pi at b_e
  double amplitude = std::numeric_limits<double>::quiet_NaN();      // A* [rad]; +inf when linear_stable
  bool valid = false;          // (b)'s conditions hold (always true for linear_stable)
  std::string invalid_reason;  // the first rule that fails: "amplitude_below_10_encoder_steps", ...
  // (c): K q <= 2 F_c; K_rest_max = 2 F_c / q (+inf without an encoder step).
  bool rest_point_ok = true;
  double K_rest_max = std::numeric_limits<double>::infinity();
};

// Throws InputError for invalid arguments.
FrictionPrediction PredictFriction(const model::Plant& plant, double period_s, int delay_samples,
                                   const LoopOptions& loop, double K, double B, const model::Friction& friction,
                                   double encoder_step, const FrictionPredictionOptions& options = {});

}  // namespace zwidth::stability
