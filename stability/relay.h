// The relay experiment of section IV (Fig. 9), simulated: a relay of amplitude
// A replaces the virtual spring, the virtual damping B (backward difference)
// is added to the relay force, and both are delayed by d samples before the
// zero-order hold. In steady state the loop oscillates near a -180 deg
// crossing of the loop L seen by the relay. The paper's reading: f_CR is the
// peak of the averaged power spectra of force and position, and K_CR is
// |F1|/|X1| there (Astrom & Hagglund's describing-function reading), which is
// biased (about -12% in K here) and, near B_t, can be a vibration mode's cycle.
// The estimate: X1/F1 is L exactly at the oscillation frequency, so relay runs
// steered to chosen frequencies (two resonators in the relay path) measure L
// where needed, find every -180 deg crossing, and keep the smallest K.
#pragma once

#include <limits>
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
  // The estimate (refined): the smallest K over the -180 deg crossings of the
  // loop, measured by relay runs steered by two resonators in the relay path,
  // each giving L exactly at its own oscillation; else the paper's reading.
  double K_cr = std::numeric_limits<double>::quiet_NaN();     // N m/rad
  double f_cr_hz = std::numeric_limits<double>::quiet_NaN();  // Hz
  bool refined = false;
  int relay_runs = 1;  // simulated runs, the plain one included
  // |L| from the first and second halves of the steady part differ by this,
  // relative (the worst of the runs behind K_cr): over 1e-3 the oscillation
  // was still settling and a longer run (--seconds) is needed.
  double unsettled = 0.0;
  // From `unsettled` and the slopes of L's phase and magnitude at the
  // crossing: a rough figure for the relative error of K_cr and f_cr when
  // refined (NaN otherwise). Measured 3-16x above the error where it exceeds
  // 1e-3; on slow models below that, up to 10x under it. Where the phase is
  // flat near -180 deg a small error in L moves the crossing far.
  double uncertainty = std::numeric_limits<double>::quiet_NaN();
  // The steered run at the lowest frequency that the record resolves (20
  // cycles in the steady part) was already past -180 deg: the critical
  // crossing lies below it (not refined; a longer --seconds reaches it).
  bool below_band = false;
  double band_low_hz = std::numeric_limits<double>::quiet_NaN();
  // The paper's reading: spectral peak, |F1|/|X1| at the peak.
  double K_cr_peak = std::numeric_limits<double>::quiet_NaN();
  double f_cr_peak_hz = std::numeric_limits<double>::quiet_NaN();
  bool oscillating = false;  // a steady oscillation was found
  // The plain run grows without bound: the loop is unstable at K = 0 (B past
  // B_max), so K_cr = K_cr_peak = 0 and the frequencies are NaN.
  bool diverged = false;
  std::vector<double> relay_force, damping_force, command, position;  // per sample
};

// Throws InputError for invalid options or model.
RelayResult SimulateRelay(const Plant& plant, const RelayOptions& options);

}  // namespace zwidth::stability
