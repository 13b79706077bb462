#include "model/simulate.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "model/c_locale.h"
#include "model/error.h"
#include "model/plant.h"
#include "model/sample_period.h"
#include "model/state_space.h"

namespace zwidth::model {

std::string EncoderStepProblem(double q, const std::string& name) {
  if (q == 0.0 || (q >= kMinEncoderStep && q <= kMaxEncoderStep)) return "";
  return name + " = " + FormatG(q) + ": an encoder step is 0 (an exact encoder) or lies in [1e-12, 1] rad (m on a "
         "linear axis) per count, e.g. 2 pi / 40960 = 0.000153398 for 40960 counts per turn";
}

bool SimulateOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (!(std::isfinite(seconds) && seconds > 0)) return bad("SimulateOptions::seconds must be > 0");
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0)) return bad("SimulateOptions::sample_rate_hz must be > 0");
  if (!(std::isfinite(torque_rms) && torque_rms > 0)) return bad("SimulateOptions::torque_rms must be > 0");
  if (torque_rms > kMaxSignalRms) {
    return bad("SimulateOptions::torque_rms = " + FormatG(torque_rms) + " is above 1e12 (N m, or N on a linear axis)");
  }
  if (!(std::isfinite(bandwidth_hz) && bandwidth_hz > 0)) return bad("SimulateOptions::bandwidth_hz must be > 0");
  if (!(std::isfinite(encoder_step_rad) && encoder_step_rad >= 0)) return bad("SimulateOptions::encoder_step_rad must be >= 0");
  if (std::string p = EncoderStepProblem(encoder_step_rad, "SimulateOptions::encoder_step_rad"); !p.empty()) return bad(p);
  if (!(std::isfinite(noise_std_rad) && noise_std_rad >= 0)) return bad("SimulateOptions::noise_std_rad must be >= 0");
  if (delay_samples < 0) return bad("SimulateOptions::delay_samples must be >= 0");
  if (delay_samples > kMaxDelaySamples) {  // the model's own plus this one may not wrap
    return bad("SimulateOptions::delay_samples " + std::to_string(delay_samples) + " is more than " +
               std::to_string(kMaxDelaySamples));
  }
  // The readers refuse a log outside their range (model/sample_period.h); a band past Nyquist aliases.
  if (!IsDeviceLogRate(sample_rate_hz)) {
    return bad("SimulateOptions::sample_rate_hz " + FormatG(sample_rate_hz) + " Hz: a device log's rate must be "
               "above 10 Hz and at most 1 MHz (the log readers refuse others); it is in Hz, e.g. 1000");
  }
  // Exactly Nyquist is the documented "white"; past it is a slip.
  if (bandwidth_hz > 0.5 * sample_rate_hz * (1.0 + 1e-12)) {
    const std::string nyquist = FormatG(0.5 * sample_rate_hz);
    return bad("SimulateOptions::bandwidth_hz " + FormatG(bandwidth_hz) + " is above Nyquist (" + nyquist +
               " Hz at SimulateOptions::sample_rate_hz " + FormatG(sample_rate_hz) + "): no sampled torque has a "
               "band there; give a band up to Nyquist (SimulateOptions::bandwidth_hz " + nyquist +
               " is white noise) or raise SimulateOptions::sample_rate_hz");
  }
  // At most kMaxSimulateSamples (4e7, 11 h at 1 kHz): `simulate` peaks at ~24 bytes a sample
  // (2e7 samples: 487 MB, 4.4 s here), so under 1 GiB; 1e8 took 2.4 GB from one flag.
  constexpr double kMaxSimulateSamples = 4e7;
  if (seconds * sample_rate_hz < 2) return bad("SimulateOptions::seconds * SimulateOptions::sample_rate_hz must give at least 2 samples");
  if (!(seconds * sample_rate_hz <= kMaxSimulateSamples)) {
    return bad("SimulateOptions::seconds x SimulateOptions::sample_rate_hz = " + FormatG(seconds * sample_rate_hz) +
               " samples, more than simulate writes (4e7); shorten SimulateOptions::seconds or lower "
               "SimulateOptions::sample_rate_hz");
  }
  return true;
}

std::vector<double> BandLimitedNoise(size_t n, double fs, double bw, double rms, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double fc = bw / fs;  // cycles per sample
  std::vector<double> out(n);
  if (fc >= 0.5) {
    for (auto& v : out) v = normal(rng);
  } else {
    const int half = static_cast<int>(std::ceil(8.0 / fc));
    std::vector<double> h(2 * half + 1);
    for (int k = -half; k <= half; ++k) {
      const double x = 2.0 * fc * k;
      const double sinc = (k == 0) ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
      const double t = static_cast<double>(k + half) / (2.0 * half);
      const double blackman = 0.42 - 0.5 * std::cos(2 * std::numbers::pi * t) +
                              0.08 * std::cos(4 * std::numbers::pi * t);
      h[k + half] = 2.0 * fc * sinc * blackman;
    }
    std::vector<double> white(n + h.size() - 1);
    for (auto& v : white) v = normal(rng);
    for (size_t i = 0; i < n; ++i) {
      double acc = 0.0;
      for (size_t j = 0; j < h.size(); ++j) acc += h[j] * white[i + j];
      out[i] = acc;
    }
  }
  double ss = 0.0;
  for (double v : out) ss += v * v;
  const double scale = rms / std::sqrt(ss / static_cast<double>(n));
  for (auto& v : out) v *= scale;
  return out;
}

void ApplySensor(const SimulateOptions& o, std::vector<double>* position) {
  std::mt19937_64 rng(o.seed ^ 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (double& y : *position) {
    if (o.encoder_step_rad > 0.0) y = o.encoder_step_rad * std::round(y / o.encoder_step_rad);
    if (o.noise_std_rad > 0.0) y += o.noise_std_rad * normal(rng);
  }
}

SimulatedLog SimulatedTorque(const Plant& plant_in, const SimulateOptions& o, Plant* plant) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  plant_in.Validate();
  *plant = plant_in;
  plant->delay_samples += o.delay_samples;
  const size_t n = static_cast<size_t>(std::llround(o.seconds * o.sample_rate_hz));
  SimulatedLog log;
  log.sample_rate_hz = o.sample_rate_hz;
  log.torque = BandLimitedNoise(n, o.sample_rate_hz, o.bandwidth_hz, o.torque_rms, o.seed);
  return log;
}

SimulatedLog SimulateLog(const Plant& plant_in, const SimulateOptions& o) {
  Plant plant;
  SimulatedLog log = SimulatedTorque(plant_in, o, &plant);
  const StateSpace d = DiscretizeZoh(plant, o.period_s());
  log.position = SimulateDiscrete(d, log.torque);
  ApplySensor(o, &log.position);
  // A position that never leaves one encoder count is a log the readers refuse (a constant
  // output): said here, in the options' words, rather than by the writer.
  if (std::all_of(log.position.begin(), log.position.end(), [&](double y) { return y == log.position[0]; })) {
    throw InputError("the simulated position is constant: every sample rounds to one encoder count "
                     "(SimulateOptions::encoder_step_rad = " + FormatG(o.encoder_step_rad) + " rad): give a finer "
                     "SimulateOptions::encoder_step_rad or a larger SimulateOptions::torque_rms");
  }
  return log;
}

}  // namespace zwidth::model
