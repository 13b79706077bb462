// The log and estimate flags of the commands that read logs (estimate, fit,
// run, batch, validate) and their resolution into the library's options.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "analysis/logs_estimate.h"
#include "ident/local_models.h"
#include "ident/welch.h"
#include "io/log.h"

namespace zwidth::flags {

struct EstimateFlags {
  io::LogSelect select;
  // window_length 0 (the default): ident::DefaultWindowLength of the first
  // log's rate and length, resolved when the log is read.
  ident::WelchOptions welch{.window_length = 0};
  std::string window = "hann", estimator = "h1";
  // none | mean | linear; "" = not given: linear, or mean with whole_record
  // (a per-segment linear detrend of a rectangular one-period segment leaks
  // the slow response's straight-line fit into every bin).
  std::string detrend;
  // Closed loop: the logged excitation (text/.mat column, HDF5 dataset); when
  // given, H = S_ry / S_ru (ident/joint.h).
  std::string reference_column, reference_dataset;
  // Each run one rectangular segment; per-bin std from the scatter between runs.
  bool whole_record = false;
  // With whole_record: one segment per period of this many samples (a
  // periodic excitation's period) instead of one per log; 0 = the whole log.
  int period_samples = 0;
  // --estimator lpm|lrm: the local methods' options (ident/local_models.h);
  // the band comes from welch.fmin_hz/fmax_hz.
  ident::LocalModelOptions local;
  bool IsLocal() const { return estimator == "lpm" || estimator == "lrm"; }
  // --estimator robust: the robust method of a periodic excitation
  // (ident/robust_frf.h), period_samples per period, each log a realisation.
  bool IsRobust() const { return estimator == "robust"; }
  int transient_periods = ident::RobustOptions{}.transient_periods;
  // Parses the enum names; throws InputError naming the flag.
  ident::WelchOptions Resolve() const;
  ident::LocalModelOptions ResolveLocal() const;  // with IsLocal()
  std::string ResolvedDetrend() const;  // detrend, or its default when not given
  // The library's options (throws InputError naming the flag).
  analysis::LogsEstimateOptions Options(bool for_fit) const;
};

void AddLogFlags(CLI::App* cmd, io::LogSelect* select);
void AddEstimateFlags(CLI::App* cmd, EstimateFlags* flags);

// --units rotary|linear: parameter labels (kg m^2, N m s/rad | kg, N s/m).
void AddUnitsFlag(CLI::App* cmd, std::string* units);
bool LinearUnits(const std::string& units);  // throws InputError for another word

}  // namespace zwidth::flags
