// The virtual wall on the nonlinear device, in the time domain (issue 32):
//
//   u_k = Act( -(K y_m + B F(z)(1 - z^-1)/T y_m) delayed D samples ),
//   y_m = the encoder's reading of the position (rounded to encoder_step),
//
// on the plant of eq. (1) with the user's hand (stability/hand.h) and
// Coulomb friction at its input, simulated exactly (model::StickSlipPlant);
// Act is the actuator's DAC step and saturation (model::Actuator). D is the
// loop delay plus the model's own. The wall is bilateral (the loop of eq. (2)
// that the Z-width is about), centred at y = 0; the device starts at rest at
// initial_position. Without friction, encoder or actuator limits this is the
// linear loop whose stability ZWidth decides.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "model/friction.h"
#include "model/plant.h"
#include "stability/loop_options.h"

namespace zwidth::stability {

struct WallOptions {
  double period_s = 0.001;        // sample period T [s], > 0
  int delay_samples = 1;          // loop delay [samples], >= 0 (the model's own delay adds)
  double stiffness = 0.0;         // K [N m/rad], in [0, 1e12]
  double damping = 0.0;           // B [N m s/rad], in [0, 1e12]
  double seconds = 10.0;          // simulated time [s], > 0; at least 64 samples, at most 5e7
  double initial_position = 0.01; // the device starts at rest here [rad], != 0, within +-1e6
  double encoder_step = 0.0;      // rad per count, >= 0; 0 = exact position
  model::Friction friction;       // at the plant input
  model::Actuator actuator;       // on the wall's force
  LoopOptions loop;               // velocity filter on the damping term, the user's hand
  bool IsValid(std::string* why) const;  // names the field: "WallOptions::seconds must be > 0"
};

enum class WallOutcome {
  kNotRun,
  kDecays,      // the motion dies out: the amplitude fell below 1e-3 of the first window's,
                // or the body stuck for the whole last window, or it shrinks steadily
  kLimitCycle,  // a steady oscillation: amplitude and frequency below
  kGrows,       // the amplitude grows steadily, or past 1e4 x the start (the run stops there)
  kUnsettled,   // none of these over the record: simulate longer (seconds)
};
std::string ToString(WallOutcome o);  // "decays", "limit_cycle", "grows", "unsettled", "not_run"

struct WallResult {
  WallOutcome outcome = WallOutcome::kNotRun;
  // Half the peak-to-peak of the true position over the last eighth of the
  // record [rad], and over the first (the start's swing).
  double amplitude = std::numeric_limits<double>::quiet_NaN();
  double initial_amplitude = std::numeric_limits<double>::quiet_NaN();
  // From the mean crossings of the last quarter [Hz]; NaN without two of them.
  double frequency_hz = std::numeric_limits<double>::quiet_NaN();
  // Amplitude ratio between the last two eighths (1 = steady).
  double last_ratio = std::numeric_limits<double>::quiet_NaN();
  double rest_position = std::numeric_limits<double>::quiet_NaN();  // mean of the last eighth [rad]
  size_t samples = 0;  // simulated (fewer than requested when it grew past the bound)
  // Per sample: the true position, the encoder's reading, the force reaching the plant.
  std::vector<double> position, measured, force;
};

// Throws InputError for invalid options or model.
WallResult SimulateWall(const model::Plant& plant, const WallOptions& options);

}  // namespace zwidth::stability
