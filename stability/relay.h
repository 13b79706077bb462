// The relay experiment of section IV (Fig. 9), simulated: a relay of amplitude
// A replaces the virtual spring, the virtual damping B (backward difference)
// is added to the relay force, and both are delayed by d samples before the
// zero-order hold. In steady state the loop oscillates near the ultimate
// frequency; as in the paper, f_CR is the peak of the averaged power spectra of
// force and position, and K_CR is |F1|/|X1|, the ratio of the first harmonics
// of the relay force and the position at that frequency (Astrom & Hagglund's
// describing-function reading of the gain margin).
#pragma once

#include <string>
#include <vector>

#include "model/plant.h"

namespace zwidth::stability {

struct RelayOptions {
  double period_s = 0.001;    // sample period T [s], > 0
  int delay_samples = 2;      // loop delay d [samples], >= 0 (the model's own delay adds)
  double damping = 0.0;       // virtual damping B [N m s/rad], >= 0
  double amplitude = 0.1;     // relay amplitude A [N m], > 0
  double seconds = 30.0;      // simulated time [s], > 0
  double settle_fraction = 0.5;  // leading fraction discarded as transient, [0, 0.9]
  bool IsValid(std::string* why) const;
};

struct RelayResult {
  // The estimate: the -180 deg crossing bracketed by relay runs with a
  // growing phase lead or lag, each giving L exactly at its own oscillation
  // frequency (refined); else (another limit cycle took over) the paper's
  // reading.
  double K_cr = 0.0;     // N m/rad
  double f_cr_hz = 0.0;  // Hz
  bool refined = false;
  // The paper's reading: spectral peak, |F1|/|X1| at the peak.
  double K_cr_peak = 0.0;
  double f_cr_peak_hz = 0.0;
  bool oscillating = false;  // a steady oscillation was found
  std::vector<double> relay_force, damping_force, command, position;  // per sample
};

// Throws InputError for invalid options or model.
RelayResult SimulateRelay(const Plant& plant, const RelayOptions& options);

}  // namespace zwidth::stability
