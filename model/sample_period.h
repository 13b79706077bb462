// The sample period T [s] of a sample rate [Hz]: the one place the period is
// derived from a rate. Every type that carries a rate (io::LogInfo,
// ident::FrequencyResponse, model::SimulateOptions/SimulatedLog, the Python
// Log) gives its period_s() through it.
#pragma once

namespace zwidth::model {

constexpr double SamplePeriod(double sample_rate_hz) { return 1.0 / sample_rate_hz; }

// The log readers' range of a device log's rate: (10 Hz, 1 MHz]. 10 Hz itself is
// refused (a 10 kHz loop logged in ms reads as exactly that), with a relative
// tolerance of 1e-9 for a rate computed from a time column. The one rule for a
// rate read from a file, given as LogSelect::sample_rate_hz, simulated
// (SimulateOptions) or made in memory (io::CheckLogSamples).
constexpr bool IsDeviceLogRate(double rate_hz) { return rate_hz > 10.0 * (1.0 + 1e-9) && rate_hz <= 1e6; }

}  // namespace zwidth::model
