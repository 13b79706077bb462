// Simulated devices and their responses for the tests of the fit's judgement
// (quality_test, order_test): logs by SimulateLog (exact ZOH plant,
// band-limited white torque, encoder quantisation), seeded, 1 kHz.
#pragma once

#include <cstdint>
#include <numbers>
#include <vector>

#include "ident/welch.h"
#include "model/plant.h"
#include "model/simulate.h"

namespace zwidth::fit {

constexpr double kHz = 2 * std::numbers::pi;

inline ident::FrequencyResponse Frf(const model::Plant& p, uint64_t seed, double seconds = 30, double bandwidth_hz = 450) {
  model::SimulateOptions so;
  so.seed = seed;
  so.seconds = seconds;
  so.bandwidth_hz = bandwidth_hz;
  so.torque_rms = 0.03 * p.m / 1.168e-3;  // the encoder's resolution weighs alike
  const model::SimulatedLog log = model::SimulateLog(p, so);
  return ident::EstimateFrequencyResponse(log.torque, log.position, so.sample_rate_hz, ident::WelchOptions{});
}

// Rigid body of Table I plus sections at the given pole frequencies [Hz], each
// zero 15 % below its pole, damping ratios 0.05 (poles) and 0.04 (zeros).
inline model::Plant Device(const std::vector<double>& poles_hz) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (double f : poles_hz) p.modes.push_back({kHz * f, 2 * 0.05 * kHz * f, kHz * 0.85 * f, 2 * 0.04 * kHz * 0.85 * f});
  return p;
}

inline const std::vector<double> kPoles[] = {{}, {120}, {60, 210}, {50, 130, 290}};

}  // namespace zwidth::fit
