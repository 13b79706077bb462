// The units of a model's quantities: a rotary axis (torque in N m, angle in
// rad) or a linear one (force in N, position in m). One table of labels for
// every table, figure, export comment and HDF5 attribute; the model file
// stores which one applies ("units", io/model_json.h).
#pragma once

namespace zwidth::model {

struct UnitLabels {
  const char* word;      // "rotary" | "linear": the model file's "units" and --units
  const char* m;         // rigid-body inertia (mass)
  const char* b;         // rigid-body viscous damping
  const char* K;         // virtual stiffness
  const char* B;         // virtual damping
  const char* H;         // the plant's response, output per input
  const char* position;  // the encoder's reading
  const char* input;     // torque or force
};

inline constexpr UnitLabels kRotaryUnits{"rotary", "kg m^2", "N m s/rad", "N m/rad", "N m s/rad", "rad/(N m)", "rad", "N m"};
inline constexpr UnitLabels kLinearUnits{"linear", "kg", "N s/m", "N/m", "N s/m", "m/N", "m", "N"};

inline const UnitLabels& Units(bool linear) { return linear ? kLinearUnits : kRotaryUnits; }

}  // namespace zwidth::model
