#include "apps/common.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "io/frf_file.h"
#include "model/error.h"

namespace zwidth::app {

const std::vector<FieldFlag>& FieldFlags() {
  static const std::vector<FieldFlag> table = {
      {"LogSelect::time_column", "--time-column"},
      {"ValidateOptions::max_lag", "--max-lag"},
      {"ValidateOptions::min_averages", ""},
      {"ValidateOptions::relative_std_floor", ""},
      {"LogSelect::input_column", "--input-column"},
      {"LogSelect::output_column", "--output-column"},
      {"LogSelect::delimiter", "--delimiter"},
      {"LogSelect::input_scale", "--input-scale"},
      {"LogSelect::output_scale", "--output-scale"},
      {"LogSelect::time_unit", "--time-unit"},
      {"LogSelect::time_dataset", "--time-dataset"},
      {"LogSelect::input_dataset", "--input-dataset"},
      {"LogSelect::output_dataset", "--output-dataset"},
      {"LogSelect::sample_rate_hz", "--rate"},
      {"ReadFrequencyResponse::sample_rate_hz", "--rate"},
      {"OutputFolder::force", "--force"},
      {"WelchOptions::window_length", "--window-length"},
      {"WelchOptions::overlap", "--overlap"},
      {"WelchOptions::fmin_hz", "--fmin"},
      {"WelchOptions::fmax_hz", "--fmax"},
      {"BandOptions::fmin_hz", "--fmin"},
      {"BandOptions::fmax_hz", "--fmax"},
      {"BandOptions::min_input_power_ratio", "--min-input-power"},
      {"BandOptions::min_coherence", "--min-coherence"},
      {"ExcitationOptions::sample_rate_hz", "--rate"},
      {"ExcitationOptions::seconds", "--seconds"},
      {"ExcitationOptions::rms", "--rms"},
      {"ExcitationOptions::fmin_hz", "--fmin"},
      {"ExcitationOptions::fmax_hz", "--fmax"},
      {"SimulateOptions::seconds", "--seconds"},
      {"SimulateOptions::sample_rate_hz", "--rate"},
      {"SimulateOptions::torque_rms", "--torque-rms"},
      {"SimulateOptions::bandwidth_hz", "--bandwidth-hz"},
      {"SimulateOptions::encoder_step_rad", "--encoder-step"},
      {"SimulateOptions::noise_std_rad", "--noise-std"},
      {"SimulateOptions::delay_samples", "--delay-samples"},
      {"FitOptions::num_modes", "--modes"},
      {"FitOptions::auto_modes", "--modes auto"},
      {"FitOptions::max_modes", "--max-modes"},
      {"FitOptions::delay_samples", "--delay-samples"},
      {"FitOptions::auto_delay", "--delay-samples auto"},
      {"FitOptions::max_auto_delay", "--max-delay"},
      {"FitOptions::allow_few_averages", "--allow-short"},
      {"FitOptions::max_iterations", "--max-iterations"},
      {"FitOptions::max_starts", "--starts"},
      {"FitOptions::init", "--init"},
      {"FitOptions::min_averages", ""},
      {"FitOptions::min_damping_ratio", ""},
      {"FitOptions::max_pole_damping_ratio", ""},
      {"FitOptions::max_zero_damping_ratio", ""},
      {"FitOptions::max_frequency_fraction", ""},
      {"FitOptions::relative_std_floor", ""},
      {"FitOptions::function_tolerance", ""},
      {"FitOptions::max_converged_starts", ""},
      {"FitOptions::runner_up_cost_ratio", ""},
      {"BGridOptions::b_min", "--b-min"},
      {"BGridOptions::b_max", "--b-max"},
      {"BGridOptions::b_step", "--b-step"},
      {"BGridOptions::b_points", "--b-points"},
      {"SummaryMonteCarlo::samples", "--monte-carlo"},
      {"SetLowPassFilter::cutoff_hz", "--velocity-filter-hz"},
      {"LoopOptions::hand", "--hand"},
      {"RunOptions::delays", "--delays"},
      {"RunOptions::report_filter_hz", "--report-filter-hz"},
      {"RelayOptions::period_s", "--period"},
      {"RelayOptions::delay_samples", "--delay"},
      {"RelayOptions::damping", "--damping"},
      {"RelayOptions::amplitude", "--amplitude"},
      {"RelayOptions::seconds", "--seconds"},
      {"RelayOptions::settle_fraction", ""},
      {"RelayOptions::loop", ""},
      {"BoundaryOptions::min_grid_points", ""},
      {"BoundaryOptions::grid_points_per_delay", ""},
      {"BoundaryOptions::theta_tolerance", ""},
      {"PassivityOptions::min_grid_points", ""},
      {"PassivityOptions::grid_points_per_delay", ""},
      {"PassivityOptions::theta_tolerance", ""},
      {"UncertaintyOptions::log_step", ""},
  };
  return table;
}

std::string WithFlags(const std::string& message) {
  std::string out;
  size_t i = 0;
  while (i < message.size()) {
    // A field is Name::name: an upper-case identifier, "::", a lower-case one.
    const size_t colon = message.find("::", i);
    if (colon == std::string::npos) break;
    size_t b = colon;
    while (b > i && (std::isalnum(static_cast<unsigned char>(message[b - 1])) || message[b - 1] == '_')) --b;
    size_t e = colon + 2;
    while (e < message.size() && (std::isalnum(static_cast<unsigned char>(message[e])) || message[e] == '_')) ++e;
    const std::string field = message.substr(b, e - b);
    const char* flag = nullptr;
    for (const FieldFlag& f : FieldFlags()) {
      if (field == f.field && *f.flag) flag = f.flag;
    }
    out += message.substr(i, b - i);
    out += flag ? std::string(flag) : field;
    i = e;
  }
  return out + message.substr(std::min(i, message.size()));
}

std::string EstimateFlags::ResolvedDetrend() const {
  if (!detrend.empty()) return detrend;
  return whole_record ? "mean" : "linear";
}

ident::WelchOptions EstimateFlags::Resolve() const {
  ident::WelchOptions o = welch;
  if (!ident::FromString(window, &o.window)) {
    throw InputError("--window '" + window + "' is not one of hann, hamming, rect");
  }
  if (!ident::FromString(ResolvedDetrend(), &o.detrend)) {
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
  cmd->add_option("--input-column", s->input_column, "input column: header name or 1-based position (text), variable (.mat)")->capture_default_str();
  cmd->add_option("--output-column", s->output_column, "output column: name or position (text), variable (.mat)")->capture_default_str();
  cmd->add_option("--time-column", s->time_column, "time column: name or position (text), variable (.mat); 'none' with --rate")->capture_default_str();
  cmd->add_option("--delimiter", s->delimiter, "text field separator: , ; tab space (default: detected)");
  cmd->add_option("--input-scale", s->input_scale, "factor applied to the input (e.g. volts -> N m)")->capture_default_str();
  cmd->add_option("--output-scale", s->output_scale, "factor applied to the output (e.g. counts -> rad)")->capture_default_str();
  cmd->add_option("--time-unit", s->time_unit, "unit of the text time column: s | ms | us (default s)");
  cmd->add_option("--input-dataset", s->input_dataset, "HDF5 dataset of the input")->capture_default_str();
  cmd->add_option("--output-dataset", s->output_dataset, "HDF5 dataset of the output")->capture_default_str();
  cmd->add_option("--time-dataset", s->time_dataset, "HDF5 dataset of the time stamps")->capture_default_str();
  cmd->add_option("--rate", s->sample_rate_hz, "sample rate [Hz], overrides the log's (time column then only checked to increase)");
}

void AddEstimateFlags(CLI::App* cmd, EstimateFlags* f) {
  AddLogFlags(cmd, &f->select);
  cmd->add_option("--window", f->window, "hann | hamming | rect (periodic)")->capture_default_str();
  cmd->add_option("--window-length", f->welch.window_length, "samples per Welch segment")->capture_default_str();
  cmd->add_option("--overlap", f->welch.overlap, "segment overlap fraction in [0, 1)")->capture_default_str();
  cmd->add_option("--detrend", f->detrend,
                  "none | mean | linear, per segment (default linear; mean with --whole-record, where linear biases "
                  "the response)");
  cmd->add_option("--estimator", f->estimator, "h1 | h2")->capture_default_str();
  cmd->add_option("--fmin", f->welch.fmin_hz, "lowest frequency kept [Hz]")->capture_default_str();
  cmd->add_option("--fmax", f->welch.fmax_hz, "highest frequency kept [Hz], clipped below Nyquist")->capture_default_str();
  cmd->add_option("--reference-column", f->reference_column, "closed loop: column/variable of the logged excitation r (H = S_ry/S_ru)");
  cmd->add_option("--reference-dataset", f->reference_dataset, "closed loop: HDF5 dataset of the logged excitation r");
  cmd->add_flag("--whole-record", f->whole_record, "each log one rectangular segment; std from the scatter between logs");
  cmd->add_option("--period-samples", f->period_samples, "with --whole-record: one segment per period of this many samples (periodic excitation)");
}

void AddUnitsFlag(CLI::App* cmd, std::string* units) {
  cmd->add_option("--units", *units, "labels: rotary (kg m^2, N m s/rad) | linear (kg, N s/m)")->capture_default_str();
}

bool LinearUnits(const std::string& units) {
  if (units == "rotary") return false;
  if (units == "linear") return true;
  throw InputError("--units '" + units.substr(0, 20) + "' is not one of rotary, linear");
}

std::string JoinPaths(const std::vector<std::string>& paths) {
  std::string s;
  for (const auto& p : paths) s += (s.empty() ? "" : " + ") + p;
  return s;
}

namespace {

void PrintRead(const io::LogInfo& info) {
  std::fprintf(stderr, "%s: %zu samples at %g Hz; %s\n", info.source.c_str(), info.num_samples,
               info.sample_rate_hz, info.layout.c_str());
  for (const auto& w : info.warnings) std::fprintf(stderr, "warning: %s: %s\n", info.source.c_str(), WithFlags(w).c_str());
}

// Samples after the last whole segment are not used: say so.
void WarnDropped(const std::string& path, size_t n_samples, const ident::WelchOptions& o) {
  const size_t n = o.window_length, step = n - o.overlap_samples();
  if (n_samples < n) return;  // Welch refuses it with a message
  const size_t segments = (n_samples - n) / step + 1;
  const size_t dropped = n_samples - ((segments - 1) * step + n);
  if (dropped == 0) return;
  std::fprintf(stderr,
               "warning: %s: the last %zu samples (%.1f %% of the log) do not fill a %zu-sample segment and are "
               "not used; a --window-length that fits, or --whole-record for a sweep or periodic excitation, uses them\n",
               path.c_str(), dropped, 100.0 * dropped / n_samples, n);
}

}  // namespace

namespace {

// --whole-record, --period-samples and --window-length that do not go together.
void CheckRecordFlags(const EstimateFlags& flags) {
  if (flags.whole_record && flags.welch.window_length != ident::WelchOptions{}.window_length) {
    throw InputError("--whole-record takes each log (or --period-samples) as one segment: drop --window-length");
  }
  if (flags.period_samples != 0 && (!flags.whole_record || flags.period_samples < 16)) {
    throw InputError("--period-samples " + std::to_string(flags.period_samples) +
                     ": needs --whole-record and a period of at least 16 samples");
  }
  if (flags.whole_record && flags.detrend == "linear") {
    std::fprintf(stderr,
                 "warning: --detrend linear with --whole-record: each rectangular segment (a whole record or period) "
                 "loses its straight-line fit, and for a periodic response that fit is not a drift but part of the "
                 "signal (a rigid body's slow swing): it leaks into every bin and biases |H| most where it is small; "
                 "--detrend mean (the --whole-record default) or none avoids it\n");
  }
}

// Closed loop: the selector that reads the logged excitation r as the "input".
io::LogSelect ExcitationSelect(const std::string& path, const EstimateFlags& flags) {
  io::LogSelect rsel = flags.select;
  const bool h5 = io::DetectLogFormat(path) == io::LogFormat::kHdf5;
  if (h5 && flags.reference_dataset.empty()) {
    throw InputError(path + ": an HDF5 log: name the excitation with --reference-dataset (not --reference-column)");
  }
  if (!h5 && flags.reference_column.empty()) {
    throw InputError(path + ": not an HDF5 log: name the excitation with --reference-column (not --reference-dataset)");
  }
  if (h5) rsel.input_dataset = flags.reference_dataset;
  else rsel.input_column = flags.reference_column;
  return rsel;
}

// Open loop in Welch segments: one streaming pass, memory for a few windows.
ident::RunSpectra StreamedRun(const std::string& path, const EstimateFlags& flags, const ident::WelchOptions& options,
                              io::LogInfo* info) {
  ident::WelchEstimator est(options);
  *info = io::StreamLog(path, flags.select, [&](const double* u, const double* y, size_t n) { est.Push(u, y, n); });
  PrintRead(*info);
  WarnDropped(path, info->num_samples, options);
  ident::RunSpectra spectra;
  spectra.uy = est.Finish(info->sample_rate_hz);
  return spectra;
}

// Each whole period of P samples one run of its own: the std is the scatter between periods.
std::vector<ident::RunSpectra> PeriodRuns(const std::string& path, const io::Log& log, const std::vector<double>& r,
                                          size_t P, ident::WelchOptions o) {
  const size_t periods = log.input.size() / P;
  if (periods == 0) {
    throw InputError("the log has " + std::to_string(log.input.size()) + " samples, fewer than one period of " +
                     std::to_string(P) + " (--period-samples)");
  }
  o.window_length = static_cast<int>(P);
  o.overlap = 0.0;
  o.window = ident::Window::kRect;
  WarnDropped(path, log.info.num_samples, o);
  std::vector<ident::RunSpectra> runs;
  for (size_t q = 0; q < periods; ++q) {
    auto cut = [&](const std::vector<double>& v) {
      return v.empty() ? v : std::vector<double>(v.begin() + q * P, v.begin() + (q + 1) * P);
    };
    runs.push_back(ident::EstimateRun(cut(log.input), cut(log.output), cut(r), log.info.sample_rate_hz, o));
  }
  return runs;
}

// The log in memory (closed loop, or --whole-record): its run, or one run per
// period with --period-samples.
std::vector<ident::RunSpectra> InMemoryRuns(const std::string& path, const EstimateFlags& flags, bool closed,
                                            const io::LogSelect& rsel, ident::WelchOptions o, io::LogInfo* info) {
  io::Log log = io::ReadLog(path, flags.select);
  *info = log.info;
  PrintRead(*info);
  std::vector<double> r;
  if (closed) {
    io::Log ex = io::ReadLog(path, rsel);
    if (ex.input.size() != log.input.size()) {
      throw InputError("the excitation has " + std::to_string(ex.input.size()) + " samples, the input " +
                       std::to_string(log.input.size()));
    }
    r = std::move(ex.input);
  }
  if (flags.whole_record && flags.period_samples > 0) {
    return PeriodRuns(path, log, r, static_cast<size_t>(flags.period_samples), o);
  }
  if (flags.whole_record) {
    if (log.input.size() > (1u << 24)) throw InputError("a whole record is limited to 2^24 samples");
    o.window_length = static_cast<int>(log.input.size());
    o.overlap = 0.0;
    o.window = ident::Window::kRect;
  } else {
    WarnDropped(path, info->num_samples, o);
  }
  std::vector<ident::RunSpectra> runs;
  runs.push_back(ident::EstimateRun(log.input, log.output, r, info->sample_rate_hz, o));
  return runs;
}

// One log's runs; an InputError names the file first.
std::vector<ident::RunSpectra> LogRuns(const std::string& path, const EstimateFlags& flags, bool closed,
                                       const ident::WelchOptions& options, io::LogInfo* info) {
  const io::LogSelect rsel = closed ? ExcitationSelect(path, flags) : flags.select;
  try {
    if (!closed && !flags.whole_record) return {StreamedRun(path, flags, options, info)};
    return InMemoryRuns(path, flags, closed, rsel, options, info);
  } catch (const InputError& e) {
    const std::string what = e.what();
    throw InputError(what.rfind(path, 0) == 0 ? what : path + ": " + what);
  }
}

// "<method> from N runs, M segments[; median coherences]" on stderr.
void PrintCombined(const ident::CombinedResponse& r) {
  std::fprintf(stderr, "%s from %d run%s, %d segments", ident::ToString(r.method).c_str(), r.num_runs,
               r.num_runs > 1 ? "s" : "", r.frf.num_averages);
  if (r.method == ident::CombinedMethod::kJoint) {
    auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    std::fprintf(stderr, "; median coherence r->u %.3f, r->y %.3f (the coherence column holds r->y)",
                 median(r.coherence_ru), median(r.coherence_ry));
  }
  std::fprintf(stderr, "\n");
}

}  // namespace

LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const EstimateFlags& flags, bool for_fit) {
  ident::WelchOptions options = flags.Resolve();
  const bool closed = !flags.reference_column.empty() || !flags.reference_dataset.empty();
  CheckRecordFlags(flags);
  // One segment: the per-bin std (the scatter between segments) would be infinite.
  auto one_segment = [&] {
    return InputError(std::string("--whole-record with one log and ") +
                      (flags.period_samples > 0 ? "one whole period of --period-samples" : "no --period-samples") +
                      " gives one segment: " +
                      (for_fit ? "no per-bin std to weight the fit" : "no scatter to estimate the per-bin std from") +
                      "; pass several runs of the same excitation, --period-samples for a periodic one, or drop "
                      "--whole-record (Welch segments)");
  };
  if (flags.whole_record && flags.period_samples == 0 && paths.size() < 2) throw one_segment();  // before reading
  LogsEstimate out;
  std::vector<ident::RunSpectra> runs;
  for (const std::string& path : paths) {
    io::LogInfo info;
    for (ident::RunSpectra& run : LogRuns(path, flags, closed, options, &info)) runs.push_back(std::move(run));
    out.total_samples += info.num_samples;
    out.infos.push_back(info);
  }
  out.response = ident::CombineRuns(runs, options.estimator,
                                    flags.whole_record ? ident::StdSource::kRunScatter : ident::StdSource::kCoherence);
  if (flags.whole_record && runs.size() < 2) throw one_segment();
  PrintCombined(out.response);
  // The stage named: estimate, before fit or write. Bins without input power
  // first (H is 0/0 there), then any other non-finite value.
  io::CheckInputPower(out.response.frf, JoinPaths(paths));
  io::CheckFiniteResponse(out.response.frf, JoinPaths(paths));
  return out;
}

double StageTimer::Lap(const std::string& stage) {
  const auto now = std::chrono::steady_clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
  if (enabled_) std::fprintf(stderr, "  %-28s %9.3f ms\n", stage.c_str(), ms);
  start_ = now;
  return ms;
}

double ResolvePeriod(double flag, io::ModelFile* mf) {
  if (std::isnan(flag)) return mf->sample_period_s ? *mf->sample_period_s : 0.001;
  if (!(flag >= kMinPeriodS && flag <= kMaxPeriodS)) {
    std::ostringstream os;
    os.precision(6);
    os << "--period = " << flag << " s: a sample period must lie in [1e-06, 0.1] s (a rate of 10 Hz..1 MHz); "
       << "--period is the period T in seconds";
    const bool rate = flag >= 10.0 && flag <= 1e6, ms = flag > 0.1 && flag <= 100.0;
    if (rate) os << ", not the rate: for " << flag << " Hz pass --period " << 1.0 / flag;
    if (ms) os << (rate ? "; " : ": ") << "for " << flag << " ms pass --period " << flag * 1e-3;
    throw InputError(os.str());
  }
  app::ConvertDelayToPeriod(mf, flag, "the model");
  return flag;
}

void ConvertDelayToPeriod(io::ModelFile* mf, double T, const std::string& what) {
  const std::string note = io::ConvertDelayToPeriod(mf, T, what);
  if (!note.empty()) std::fprintf(stderr, "note: %s\n", note.c_str());
}

namespace {
std::string& StoredCommandLine() {
  static std::string line;
  return line;
}
}  // namespace

void SetCommandLine(int argc, char** argv) {
  std::string& line = StoredCommandLine();
  line.clear();
  for (int i = 0; i < argc; ++i) {
    const std::string a = i == 0 ? "zwidth" : argv[i];
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                         "0123456789-_./=:,+@%") == std::string::npos;
    std::string q = a;
    if (!plain) {
      q = "'";
      for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
      q += "'";
    }
    line += (i ? " " : "") + q;
  }
}

const std::string& CommandLine() { return StoredCommandLine(); }

}  // namespace zwidth::app
