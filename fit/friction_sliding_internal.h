// The friction fit's simulations of the device with Coulomb friction, from
// the measured torque (fit/friction_fit.cc uses them; not installed).
#pragma once

#include <vector>

#include "model/plant.h"

namespace zwidth::fit::internal {

// The rigid body with friction, simulated exactly (events at v = 0) from the
// measured torque: per sample interval the average of sign(v) while moving
// and the fraction of it spent moving. Its velocity converges to the
// device's whatever the start (the friction is monotone in v: two solutions'
// difference decays), so it gives the switching instants at full bandwidth,
// free of the encoder's noise.
struct Sliding {
  std::vector<double> sign, moving;
  std::vector<double> position;  // x(jT), from 0 at the start (the instrument of FrequencyIdim)
  // The average net plant input while stuck (u + offset + the holding
  // friction): 0 on the rigid body, whose acceleration is 0 at rest; on the
  // collocated plant -C A^2 x / g (the sections keep moving).
  std::vector<double> held;
  // position is the encoder's y(jT) (collocated), not the rigid body's x(jT).
  bool position_is_encoder = false;
};

// The rigid body m, b with friction fc and offset, from velocity v0.
Sliding SimulateRigidBody(const std::vector<double>& U, double fs, double m, double b, double fc, double offset,
                          double v0);
// eq. (1)'s plant with the friction at the collocated encoder (position is y(jT)).
Sliding SimulateCollocated(const std::vector<double>& U, double fs, const model::Plant& plant, double fc,
                           double offset);

}  // namespace zwidth::fit::internal
