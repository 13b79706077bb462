#include "apps/common.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <sstream>

#include "io/frf_file.h"
#include "io/option_names.h"
#include "io/printable.h"
#include "model/error.h"

namespace zwidth::app {

// The table of fields, flags and keywords is io/option_names.cc (shared with the Python module).
std::string WithFlags(const std::string& message) { return io::WithFlags(message); }

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
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
  if (!IsLocal() && !ident::FromString(estimator, &o.estimator)) {
    throw InputError("--estimator '" + estimator + "' is not one of h1, h2, lpm, lrm");
  }
  std::string why;
  ident::WelchOptions check = o;
  if (check.window_length == 0) check.window_length = ident::WelchOptions{}.window_length;  // resolved per log
  if (!check.IsValid(&why)) throw InputError(why);
  return o;
}

ident::LocalModelOptions EstimateFlags::ResolveLocal() const {
  ident::LocalModelOptions o = local;
  ident::FromString(estimator, &o.method);
  o.fmin_hz = welch.fmin_hz;
  o.fmax_hz = welch.fmax_hz;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(WithFlags(why));
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
  cmd->add_option("--input-unit", s->input_unit, "unit of the text input column (mN m, N mm, N, ...; si: as is; default: from the header, else N m)");
  cmd->add_option("--output-unit", s->output_unit, "unit of the text output column (deg, rad, mm, um, m, counts, ...; si: as is; default: from the header, else rad)");
  cmd->add_option("--counts-per-rev", s->counts_per_rev, "encoder counts per turn, for an output in counts (to rad)");
  cmd->add_option("--counts-per-m", s->counts_per_m, "encoder counts per metre, for an output in counts (to m)");
  cmd->add_flag("--decimal-comma", s->decimal_comma, "text numbers use ',' as the decimal mark (detected when the first data line reads only so)");
  cmd->add_option("--input-dataset", s->input_dataset, "HDF5 dataset of the input")->capture_default_str();
  cmd->add_option("--output-dataset", s->output_dataset, "HDF5 dataset of the output")->capture_default_str();
  cmd->add_option("--time-dataset", s->time_dataset, "HDF5 dataset of the time stamps")->capture_default_str();
  cmd->add_option("--rate", s->sample_rate_hz, "sample rate [Hz], overrides the log's (time column then only checked to increase)");
}

void AddEstimateFlags(CLI::App* cmd, EstimateFlags* f) {
  AddLogFlags(cmd, &f->select);
  cmd->add_option("--window", f->window, "hann | hamming | rect (periodic)")->capture_default_str();
  cmd->add_option("--window-length", f->welch.window_length,
                  "samples per Welch segment (default: the power of two nearest 4.096 s at the log's rate, halved until "
                  "the log holds 3 segments: 4096 at 1 kHz, 16384 at 5 kHz)");
  cmd->add_option("--overlap", f->welch.overlap, "segment overlap fraction in [0, 1)")->capture_default_str();
  cmd->add_option("--detrend", f->detrend,
                  "none | mean | linear, per segment (default linear; mean with --whole-record, where linear biases "
                  "the response)");
  cmd->add_option("--estimator", f->estimator,
                  "h1 | h2 (Welch) | lpm | lrm (local polynomial / rational method on the whole record, "
                  "docs/estimators.md)")->capture_default_str();
  cmd->add_option("--local-half-width", f->local.half_width,
                  "lpm/lrm: bins either side of each estimate (0: 6 for lpm, 7 for lrm)")->capture_default_str();
  cmd->add_option("--local-order", f->local.order, "lpm/lrm: order of the local polynomials (lrm: numerators)")->capture_default_str();
  cmd->add_option("--local-denominator-order", f->local.denominator_order, "lrm: order of the local denominator")->capture_default_str();
  cmd->add_option("--local-differences", f->local.differences,
                  "lpm/lrm: times the output is differenced first (2: the rigid body's poles at z = 1 removed)")->capture_default_str();
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
  const std::string source = io::Printable(info.source);
  std::fprintf(stderr, "%s: %zu samples at %g Hz; %s\n", source.c_str(), info.num_samples, info.sample_rate_hz,
               io::Printable(info.layout).c_str());
  for (const auto& w : info.warnings) {
    std::fprintf(stderr, "warning: %s: %s\n", source.c_str(), io::Printable(WithFlags(w)).c_str());
  }
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
               io::Printable(path).c_str(), dropped, 100.0 * dropped / n_samples, n);
}

}  // namespace

namespace {

// --whole-record, --period-samples and --window-length that do not go together.
void CheckRecordFlags(const EstimateFlags& flags) {
  if (flags.whole_record && flags.welch.window_length != 0) {
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
// The default window (window_length 0) needs the log's rate and length, known
// at its end: the first kAutoWindowBuffer samples are held until then; a longer
// log is estimated with the window of its rate at 1 kHz (4096) as it streams,
// and read a second time when its rate asks for another one.
ident::RunSpectra StreamedRun(const std::string& path, const EstimateFlags& flags, ident::WelchOptions o,
                              io::LogInfo* info, std::uint64_t* fingerprint) {
  constexpr size_t kAutoWindowBuffer = size_t{1} << 17;  // 2 MiB of samples
  const bool auto_window = o.window_length == 0;
  std::vector<double> held_u, held_y;
  if (auto_window) held_u.reserve(kAutoWindowBuffer), held_y.reserve(kAutoWindowBuffer);
  std::unique_ptr<ident::WelchEstimator> est;
  if (!auto_window) est = std::make_unique<ident::WelchEstimator>(o);
  io::LogFingerprint fp;
  *info = io::StreamLog(path, flags.select, [&](const double* u, const double* y, size_t n) {
    fp.Add(u, y, n);
    if (!est && held_u.size() + n <= kAutoWindowBuffer) {
      held_u.insert(held_u.end(), u, u + n);
      held_y.insert(held_y.end(), y, y + n);
      return;
    }
    if (!est) {  // longer than the buffer: the window of a long log at 1 kHz, checked at the end
      o.window_length = ident::DefaultWindowLength(1000.0, kAutoWindowBuffer);
      est = std::make_unique<ident::WelchEstimator>(o);
      est->Push(held_u.data(), held_y.data(), held_u.size());
      held_u = {}, held_y = {};
    }
    est->Push(u, y, n);
  });
  *fingerprint = fp.value();
  PrintRead(*info);
  if (auto_window) {
    const int want = ident::DefaultWindowLength(info->sample_rate_hz, info->num_samples);
    if (!est || want != o.window_length) {
      o.window_length = want;
      est = std::make_unique<ident::WelchEstimator>(o);
      if (!held_u.empty()) est->Push(held_u.data(), held_y.data(), held_u.size());
      else io::StreamLog(path, flags.select, [&](const double* u, const double* y, size_t n) { est->Push(u, y, n); });
    }
  }
  WarnDropped(path, info->num_samples, o);
  ident::RunSpectra spectra;
  spectra.uy = est->Finish(info->sample_rate_hz);
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
                                            const io::LogSelect& rsel, ident::WelchOptions o, io::LogInfo* info,
                                            std::uint64_t* fingerprint) {
  io::Log log = io::ReadLog(path, flags.select);
  *info = log.info;
  io::LogFingerprint fp;
  fp.Add(log.input.data(), log.output.data(), log.input.size());
  *fingerprint = fp.value();
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
  if (o.window_length == 0) o.window_length = ident::DefaultWindowLength(info->sample_rate_hz, info->num_samples);
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
                                       const ident::WelchOptions& options, io::LogInfo* info,
                                       std::uint64_t* fingerprint) {
  const io::LogSelect rsel = closed ? ExcitationSelect(path, flags) : flags.select;
  try {
    if (!closed && !flags.whole_record) return {StreamedRun(path, flags, options, info, fingerprint)};
    return InMemoryRuns(path, flags, closed, rsel, options, info, fingerprint);
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

// The same samples twice (a file given twice, a copy, a link) are not two
// runs: averaged, they shrink every per-bin std by 1/sqrt(2). Refused, since
// no use of it is right; the message names both.
void RefuseRepeatedLog(const std::vector<std::string>& paths, const std::vector<std::uint64_t>& seen,
                       std::uint64_t fingerprint, const std::string& path) {
  for (size_t i = 0; i < seen.size(); ++i) {
    if (seen[i] != fingerprint) continue;
    throw InputError(path + " holds the same samples as " + paths[i] +
                     " (the same file, a copy or a link): runs are averaged as independent, and the same data twice "
                     "would shrink every std by 1/sqrt(2) while adding nothing; give each run once");
  }
}

}  // namespace

namespace {

// --estimator lpm|lrm: every log read whole (with its excitation in closed
// loop), one local estimate over all of them.
LogsEstimate EstimateLocalFromLogs(const std::vector<std::string>& paths, const EstimateFlags& flags, bool closed) {
  if (flags.whole_record || flags.period_samples != 0 || flags.welch.window_length != 0 ||
      flags.welch.overlap != ident::WelchOptions{}.overlap) {
    throw InputError("--estimator " + flags.estimator + " fits a local model on each whole log: drop --whole-record, "
                     "--period-samples, --window-length and --overlap (Welch options)");
  }
  const ident::LocalModelOptions o = flags.ResolveLocal();
  LogsEstimate out;
  std::vector<ident::LocalRecord> runs;
  double rate = 0.0;
  for (const std::string& path : paths) {
    try {
      io::Log log = io::ReadLog(path, flags.select);
      PrintRead(log.info);
      ident::LocalRecord run{std::move(log.input), std::move(log.output), {}};
      if (closed) run.r = std::move(io::ReadLog(path, ExcitationSelect(path, flags)).input);
      if (rate == 0.0) rate = log.info.sample_rate_hz;
      if (std::abs(log.info.sample_rate_hz - rate) > 1e-3 * rate) {
        throw InputError("the log's rate differs from the first log's: runs of one estimate need one rate");
      }
      out.total_samples += log.info.num_samples;
      out.infos.push_back(log.info);
      runs.push_back(std::move(run));
    } catch (const InputError& e) {
      const std::string what = e.what();
      throw InputError(what.rfind(path, 0) == 0 ? what : path + ": " + what);
    }
  }
  ident::LocalEstimate est = ident::EstimateLocal(runs, rate, o);
  for (const std::string& w : est.warnings) std::fprintf(stderr, "warning: %s\n", WithFlags(w).c_str());
  out.response = ident::ToCombined(std::move(est), o.method, static_cast<int>(runs.size()));
  std::fprintf(stderr, "%s (%s) from %zu run%s, %d bins per local window, %d residual degrees of freedom\n",
               ident::ToString(out.response.method).c_str(), out.response.frf.estimator.c_str(), runs.size(),
               runs.size() > 1 ? "s" : "", 2 * o.HalfWidth() + 1, out.response.frf.num_averages);
  return out;
}

}  // namespace

LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const EstimateFlags& flags, bool for_fit) {
  if (flags.IsLocal()) {
    LogsEstimate out = EstimateLocalFromLogs(paths, flags, !flags.reference_column.empty() || !flags.reference_dataset.empty());
    io::CheckInputPower(out.response.frf, JoinPaths(paths));
    io::CheckFiniteResponse(out.response.frf, JoinPaths(paths));
    return out;
  }
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
  std::vector<std::uint64_t> seen;  // one fingerprint per log read
  for (const std::string& path : paths) {
    io::LogInfo info;
    std::uint64_t fingerprint = 0;
    for (ident::RunSpectra& run : LogRuns(path, flags, closed, options, &info, &fingerprint)) {
      runs.push_back(std::move(run));
    }
    // The default window, resolved on the first log, is every run's (runs combine alike).
    if (options.window_length == 0 && !runs.empty()) options.window_length = runs.front().uy.window_length;
    RefuseRepeatedLog(paths, seen, fingerprint, path);
    seen.push_back(fingerprint);
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
  if (const std::string why = io::SamplePeriodProblem(flag, "--period"); !why.empty()) throw InputError(why);
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
