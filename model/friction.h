// The nonlinear parts of a real device that eq. (1) leaves out: Coulomb
// friction on the rigid body (asymmetric, with a constant offset and an
// optional breakaway level), and the actuator's limits (torque saturation, DAC
// step). The encoder step is a sensor property and lives with the simulation.
//
// Friction acts where the motor torque does (the plant input, eq. (1)'s rigid
// body), in the input's units (N m for a rotary model, N for a linear one):
//   moving, v > 0:  tau_f = -coulomb_pos + offset
//   moving, v < 0:  tau_f = +coulomb_neg + offset
//   at rest:        the body stays at rest while |u + offset| <= breakaway level
//                   (breakaway_pos / breakaway_neg; 0 = the Coulomb level)
// `offset` is a constant torque (gravity on a tilted axis, an amplifier bias):
// it acts whether the body moves or not.
#pragma once

#include <string>

namespace zwidth::model {

struct Friction {
  double coulomb_pos = 0.0;    // Coulomb level opposing v > 0, >= 0
  double coulomb_neg = 0.0;    // Coulomb level opposing v < 0 (a magnitude), >= 0
  double offset = 0.0;         // constant input offset, any sign
  double breakaway_pos = 0.0;  // static level for starting with v > 0; 0 = coulomb_pos, else >= it
  double breakaway_neg = 0.0;  // static level for starting with v < 0; 0 = coulomb_neg, else >= it

  // A symmetric Coulomb friction of level fc.
  static Friction Symmetric(double fc) { return {fc, fc, 0.0, 0.0, 0.0}; }

  // No friction and no offset.
  bool IsZero() const {
    return coulomb_pos == 0.0 && coulomb_neg == 0.0 && offset == 0.0 && breakaway_pos == 0.0 && breakaway_neg == 0.0;
  }
  // (coulomb_pos + coulomb_neg) / 2: the level a describing function uses.
  double MeanCoulomb() const { return 0.5 * (coulomb_pos + coulomb_neg); }
  double StaticPos() const { return breakaway_pos > 0.0 ? breakaway_pos : coulomb_pos; }
  double StaticNeg() const { return breakaway_neg > 0.0 ? breakaway_neg : coulomb_neg; }

  // Finite, levels >= 0, a breakaway level 0 or >= its Coulomb level, all
  // magnitudes <= 1e12. Otherwise *why names the field ("coulomb_pos = -1: ...").
  bool IsValid(std::string* why) const;
  // Throws InputError with IsValid's message.
  void Validate() const;
};

// Limits of the actuator. 0 = none.
struct Actuator {
  double saturation = 0.0;  // |u| clipped to this [input units], >= 0
  double dac_step = 0.0;    // u rounded to a multiple of this [input units], >= 0

  bool IsZero() const { return saturation == 0.0 && dac_step == 0.0; }
  bool IsValid(std::string* why) const;
  // u as the actuator delivers it: rounded to the DAC step, then saturated.
  double Apply(double u) const;
};

}  // namespace zwidth::model
