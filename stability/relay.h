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
//
// The loop may be the haptic loop of stability/loop_options.h (issue 16): the
// damping acts on the filtered velocity B F(z)(1 - z^-1)/T and the user's hand
// is on the plant (sampled exactly by ZOH from its state space), so the relay
// estimates K_CR(B) of ZWidth(plant, T, d, loop).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "model/friction.h"
#include "model/plant.h"
#include "stability/loop_options.h"

namespace zwidth::stability {

struct RelayOptions {
  double period_s = 0.001;    // sample period T [s], > 0
  int delay_samples = 2;      // loop delay d [samples], >= 0 (the model's own delay adds)
  double damping = 0.0;       // virtual damping B [N m s/rad], >= 0
  double amplitude = 0.1;     // relay amplitude A [N m], > 0
  double seconds = 30.0;      // simulated time [s], > 0
  double settle_fraction = 0.5;  // leading fraction discarded as transient, [0, 0.9]
  LoopOptions loop;  // velocity filter F(z) on the damping term and the user's hand; default: the paper's loop
  // The device's nonlinear parts (issue 32): Coulomb friction at the plant
  // input (simulated exactly, model/nonlinear_simulate.h), the actuator's DAC
  // step and saturation on the command, the encoder's step on the position
  // the relay and the damping see [rad, >= 0; 0 = exact]. Default: none (the linear loop).
  model::Friction friction;
  model::Actuator actuator;
  double encoder_step = 0.0;
  // False: the plain relay run only, the paper's reading (K_cr = K_cr_peak,
  // status kPeakReading when it oscillates), one run instead of ~30 steered ones.
  bool refine = true;
  bool Nonlinear() const { return !friction.IsZero() || !actuator.IsZero() || encoder_step > 0.0; }
  bool IsValid(std::string* why) const;  // names the field: "RelayOptions::seconds must be > 0"
};

// What the relay run gave, and which numbers of RelayResult can be used.
enum class RelayStatus {
  kNotRun,         // no result (default)
  kRefined,        // K_cr, f_cr_hz from the steered runs (exact crossing; see `uncertainty`)
  kPeakReading,    // oscillating, but no -180 deg crossing found by the steered runs:
                   // K_cr, f_cr_hz are the paper's reading (biased)
  kBelowBand,      // the steered run at the lowest frequency the record resolves was already past
                   // -180 deg: the crossing lies below band_low_hz; K_cr is the paper's reading,
                   // a longer record (seconds) reaches it
  kDiverged,       // the plain relay run grows without bound: the loop is unstable as K -> 0+
                   // (B past B_max_from_zero), K_cr = K_cr_peak = 0, frequencies NaN
  kNoOscillation,  // neither a steady oscillation nor divergence: no number is usable
};
std::string ToString(RelayStatus s);  // "refined", "peak_reading", "below_band", "diverged", ...
RelayStatus RelayStatusFromString(const std::string& s);  // InputError for an unknown name

struct RelayResult {
  // The estimate (refined): the smallest K over the -180 deg crossings of the
  // loop, measured by relay runs steered by two resonators in the relay path,
  // each giving L exactly at its own oscillation; else the paper's reading.
  double K_cr = std::numeric_limits<double>::quiet_NaN();     // N m/rad
  double f_cr_hz = std::numeric_limits<double>::quiet_NaN();  // Hz
  RelayStatus status = RelayStatus::kNotRun;
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
  // The lowest frequency that the record resolves (20 cycles in the steady
  // part): the lowest steered run (kBelowBand when it is past -180 deg).
  double band_low_hz = std::numeric_limits<double>::quiet_NaN();
  // The paper's reading: spectral peak, |F1|/|X1| at the peak.
  double K_cr_peak = std::numeric_limits<double>::quiet_NaN();
  double f_cr_peak_hz = std::numeric_limits<double>::quiet_NaN();
  // Derived from status.
  bool refined() const { return status == RelayStatus::kRefined; }
  bool oscillating() const {
    return status == RelayStatus::kRefined || status == RelayStatus::kPeakReading ||
           status == RelayStatus::kBelowBand;
  }
  // The plain run, per sample: relay force, damping force -B F(z)(1 - z^-1)/T y,
  // their sum (the command before the delay) and the position y.
  std::vector<double> relay_force, damping_force, command, position;
};

// Throws InputError for invalid options or model (never ComputationError: a
// loop that does not oscillate gives kNoOscillation).
RelayResult SimulateRelay(const model::Plant& plant, const RelayOptions& options);

}  // namespace zwidth::stability
