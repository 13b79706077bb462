// The sample period T [s] of a sample rate [Hz]: the one place the period is
// derived from a rate. Every type that carries a rate (io::LogInfo,
// ident::FrequencyResponse, model::SimulateOptions/SimulatedLog, the Python
// Log) gives its period_s() through it.
#pragma once

namespace zwidth::model {

constexpr double SamplePeriod(double sample_rate_hz) { return 1.0 / sample_rate_hz; }

}  // namespace zwidth::model
