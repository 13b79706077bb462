// The frequency response of one device from its logs: one or several runs,
// Welch segments streamed (open loop) or records in memory (closed loop with
// a logged excitation, whole records, periods of a periodic excitation), or
// the local polynomial / rational method on each whole log. The one place
// that rule lives: `zwidth estimate`, `fit` and `run` and the Python module's
// estimate_logs() call it; it prints nothing (what a caller shows as it
// reads goes to `note`).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ident/joint.h"
#include "ident/local_models.h"
#include "ident/robust_frf.h"
#include "ident/welch.h"
#include "io/log.h"

namespace zwidth::analysis {

struct LogsEstimateOptions {
  io::LogSelect select;
  // Welch: window, detrend, estimator h1/h2, band (fmin/fmax also bound the
  // local methods' band). window_length 0 (the default): the first log's
  // ident::DefaultWindowLength of its rate and length, every run's.
  ident::WelchOptions welch{.window_length = 0};
  // The local polynomial / rational method instead of Welch (ident/local_models.h).
  std::optional<ident::LocalModelOptions> local;
  // The robust method of a periodic excitation instead (ident/robust_frf.h):
  // each log one random-phase realisation of P periods of
  // RobustOptions::period_samples; the band is RobustOptions::fmin_hz/fmax_hz.
  std::optional<ident::RobustOptions> robust;
  // Closed loop: the logged excitation r (a text/.mat column, an HDF5
  // dataset: the one the log's format reads); H = S_ry / S_ru (ident/joint.h).
  std::string reference_column, reference_dataset;
  // Each run one rectangular segment; per-bin std from the scatter between runs.
  bool whole_record = false;
  // With whole_record: one segment per period of this many samples (>= 16).
  int period_samples = 0;
  // The response is for a fit: one segment (no per-bin std) is refused
  // rather than returned with an infinite std.
  bool for_fit = false;

  bool ClosedLoop() const { return !reference_column.empty() || !reference_dataset.empty(); }
};

// The per-segment detrend when none is chosen: linear for Welch segments;
// mean for whole records and periods, where a linear fit is not a drift but
// part of a periodic response (a rigid body's slow swing) and leaks into
// every bin.
inline ident::Detrend DefaultDetrend(bool whole_record) {
  return whole_record ? ident::Detrend::kMean : ident::Detrend::kLinear;
}

struct LogsEstimate {
  ident::CombinedResponse response;
  std::vector<io::LogInfo> infos;  // one per log, in order
  std::size_t total_samples = 0;
};

// A line for the user as the logs are read: "PATH: N samples at R Hz; LAYOUT",
// "warning: PATH: ..." and the estimate's summary, naming option fields
// (io/option_names.h) and the file names as given (io::Printable them).
using EstimateNote = std::function<void(const std::string& line)>;

// The robust method chosen (robust) or not from the estimate's own fields, as
// the CLI's --estimator robust and Python's estimator='robust' ask for it:
// LogsEstimateOptions::period_samples becomes RobustOptions::period_samples
// (and 0 itself), the band WelchOptions::fmin_hz/fmax_hz, with
// transient_periods. Throws InputError naming the field for invalid options,
// and for a transient_periods other than the default without the robust method.
void ChooseRobust(LogsEstimateOptions* options, bool robust, int transient_periods);

// The one rule of how long a log must be for a Welch estimate (the CLI's
// estimate, fit, run, batch units; Python's estimate, fit and run): with the
// default window (default_window: o.window_length is DefaultWindowLength's),
// 3 segments of 50 % overlap of at least ident::ShortestDefaultWindow, the
// FitOptions::min_averages a per-bin std needs; with a window given, one
// segment (fewer than 3 are the fit's to refuse or allow,
// FitOptions::allow_few_averages). o: the resolved options (window_length >
// 0). Throws InputError saying how long the log is and must be, in samples
// and seconds, and what to do; called before the spectra are computed.
void CheckLogLength(size_t num_samples, double rate_hz, const ident::WelchOptions& o, bool default_window);

// Throws InputError naming the file first for a log that cannot be read or
// options that do not go together, and for the same samples given twice (a
// file, its copy or a link: averaged as two runs they would shrink every std
// by 1/sqrt(2)).
LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const LogsEstimateOptions& options,
                              const EstimateNote& note = {});

}  // namespace zwidth::analysis
