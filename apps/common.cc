#include "apps/common.h"

#include <cstdio>

#include "io/frf_file.h"
#include "model/error.h"

namespace zwidth::app {

ident::WelchOptions EstimateFlags::Resolve() const {
  ident::WelchOptions o = welch;
  if (!ident::FromString(window, &o.window)) {
    throw InputError("--window '" + window + "' is not one of hann, hamming, rect");
  }
  if (!ident::FromString(detrend, &o.detrend)) {
    throw InputError("--detrend '" + detrend + "' is not one of none, mean, linear");
  }
  if (!ident::FromString(estimator, &o.estimator)) {
    throw InputError("--estimator '" + estimator + "' is not one of h1, h2");
  }
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  return o;
}

void AddLogFlags(CLI::App* cmd, io::LogSelect* s) {
  cmd->add_option("--input-column", s->input_column, "CSV column of the torque input")->capture_default_str();
  cmd->add_option("--output-column", s->output_column, "CSV column of the position output")->capture_default_str();
  cmd->add_option("--time-column", s->time_column, "CSV column of the time stamps [s]")->capture_default_str();
  cmd->add_option("--input-dataset", s->input_dataset, "HDF5 dataset of the input")->capture_default_str();
  cmd->add_option("--output-dataset", s->output_dataset, "HDF5 dataset of the output")->capture_default_str();
  cmd->add_option("--time-dataset", s->time_dataset, "HDF5 dataset of the time stamps")->capture_default_str();
  cmd->add_option("--rate", s->sample_rate_hz, "sample rate [Hz], overrides the log's");
}

void AddEstimateFlags(CLI::App* cmd, EstimateFlags* f) {
  AddLogFlags(cmd, &f->select);
  cmd->add_option("--window", f->window, "hann | hamming | rect (periodic)")->capture_default_str();
  cmd->add_option("--window-length", f->welch.window_length, "samples per Welch segment")->capture_default_str();
  cmd->add_option("--overlap", f->welch.overlap, "segment overlap fraction in [0, 1)")->capture_default_str();
  cmd->add_option("--detrend", f->detrend, "none | mean | linear (per segment)")->capture_default_str();
  cmd->add_option("--estimator", f->estimator, "h1 | h2")->capture_default_str();
  cmd->add_option("--fmin", f->welch.fmin_hz, "lowest frequency kept [Hz]")->capture_default_str();
  cmd->add_option("--fmax", f->welch.fmax_hz, "highest frequency kept [Hz], clipped below Nyquist")->capture_default_str();
}

ident::FrequencyResponse EstimateFromLog(const std::string& path, const EstimateFlags& flags,
                                         io::LogInfo* info_out) {
  const ident::WelchOptions options = flags.Resolve();
  ident::WelchEstimator est(options);
  const io::LogInfo info = io::StreamLog(path, flags.select,
      [&](const double* u, const double* y, size_t n) { est.Push(u, y, n); });
  if (info_out) *info_out = info;
  ident::FrequencyResponse frf;
  try {
    frf = est.Finish(info.sample_rate_hz);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  io::CheckFiniteResponse(frf, path);  // the stage named: estimate, before fit or write
  return frf;
}

double StageTimer::Lap(const std::string& stage) {
  const auto now = std::chrono::steady_clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
  if (enabled_) std::fprintf(stderr, "  %-28s %9.3f ms\n", stage.c_str(), ms);
  start_ = now;
  return ms;
}

}  // namespace zwidth::app
