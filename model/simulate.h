// Simulated device logs: band-limited white-noise torque through the exact
// sampled plant (torque held over each period, angle sampled at the start of
// the period), then encoder quantisation and sensor noise.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/plant.h"
#include "model/sample_period.h"

namespace zwidth::model {

// An encoder step q [rad, or m on a linear axis, per count] is 0 (an exact
// encoder) or lies in [kMinEncoderStep, kMaxEncoderStep]: a step above 1 rad
// rounds every motion of a haptic device to one count (a wall simulated with
// --encoder-step 1e300 "decayed", a relay "did not oscillate"). The one rule
// for a flag, a keyword, an option and a model file's "encoder_step".
inline constexpr double kMinEncoderStep = 1e-12, kMaxEncoderStep = 1.0;
// "" when q is allowed, else a message naming `name`.
std::string EncoderStepProblem(double q, const std::string& name);

// A signal's RMS (a simulated torque, an excitation) is at most kMaxSignalRms
// [input units]: past it the log's spectra overflow (1e300 was written, then
// refused by every reader) long before any actuator could give it.
inline constexpr double kMaxSignalRms = 1e12;

struct SimulateOptions {
  double seconds = 30.0;             // log length [s], > 0; seconds x sample_rate_hz in [2, 4e7] samples
  double sample_rate_hz = 1000.0;    // [Hz], in (10, 1e6]: the log readers' range (IsDeviceLogRate)
  double period_s() const { return SamplePeriod(sample_rate_hz); }  // the sample period T [s]
  double torque_rms = 0.03;          // RMS of the torque [N m], > 0
  double bandwidth_hz = 300.0;       // torque band limit [Hz], in (0, Nyquist]; Nyquist = white
  double encoder_step_rad = 2.0 * 3.14159265358979323846 / 40960.0;  // rad per count; 0 = none
  double noise_std_rad = 0.0;        // additive Gaussian sensor noise [rad], >= 0
  int delay_samples = 0;             // extra input delay [samples], in [0, kMaxDelaySamples] (adds to the model's)
  uint64_t seed = 1;

  bool IsValid(std::string* why) const;
};

struct SimulatedLog {
  double sample_rate_hz = 0.0;
  double period_s() const { return SamplePeriod(sample_rate_hz); }  // the sample period T [s]
  std::vector<double> torque;    // N m
  std::vector<double> position;  // rad
};

// The start of every simulated log: options and plant validated (InputError),
// the torque of `options` made, the plant's delay raised by options.delay_samples.
// The caller fills `position`.
SimulatedLog SimulatedTorque(const Plant& plant, const SimulateOptions& options, Plant* delayed_plant);

// Throws InputError for invalid options or model.
SimulatedLog SimulateLog(const Plant& plant, const SimulateOptions& options);

// The encoder step, then the sensor noise of `options`, applied to positions in
// place (the noise seeded from options.seed as SimulateLog does).
void ApplySensor(const SimulateOptions& options, std::vector<double>* position);

// Band-limited white noise: Gaussian white noise filtered by a linear-phase
// windowed-sinc low-pass (Blackman, 8 cut-off periods each side), scaled to the
// exact RMS. Exposed for tests.
std::vector<double> BandLimitedNoise(size_t n, double sample_rate_hz, double bandwidth_hz,
                                     double rms, uint64_t seed);

}  // namespace zwidth::model
