// Command-line flags of the device's nonlinear parts (issue 32): Coulomb
// friction, its offset and breakaway level, the actuator's saturation and DAC
// step; shared by simulate, wall and relay.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "io/model_json.h"
#include "model/friction.h"

namespace zwidth::app {

struct FrictionFlags {
  double coulomb = 0.0, coulomb_pos = 0.0, coulomb_neg = 0.0, offset = 0.0, breakaway = 0.0;
  double saturation = 0.0, dac_step = 0.0;
  bool no_model_friction = false;
  // Set by AddFrictionFlags: whether each friction flag was given.
  CLI::Option *coulomb_opt = nullptr, *coulomb_pos_opt = nullptr, *coulomb_neg_opt = nullptr,
              *offset_opt = nullptr, *breakaway_opt = nullptr;
};

void AddFrictionFlags(CLI::App* cmd, FrictionFlags* flags);

// The friction: the model file's "friction" unless a friction flag is given
// (then the flags alone, unset levels 0) or --no-model-friction. Throws
// InputError naming the flag (NaN, inf, negative, --coulomb with
// --coulomb-pos/--coulomb-neg, a breakaway below a Coulomb level).
model::Friction ResolveFriction(const FrictionFlags& flags, const io::ModelFile& mf);
// Throws InputError naming --torque-saturation or --dac-step.
model::Actuator ResolveActuator(const FrictionFlags& flags);

}  // namespace zwidth::app
