#include "analysis/logs_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

#include "io/frf_file.h"
#include "model/error.h"
#include "model/sample_period.h"

namespace zwidth::analysis {
namespace {

void Note(const EstimateNote& note, const std::string& line) {
  if (note) note(line);
}

std::string JoinPaths(const std::vector<std::string>& paths) {
  std::string s;
  for (const auto& p : paths) s += (s.empty() ? "" : " + ") + p;
  return s;
}

void NoteRead(const EstimateNote& note, const io::LogInfo& info) {
  char head[96];
  std::snprintf(head, sizeof head, ": %zu samples at %g Hz; ", info.num_samples, info.sample_rate_hz);
  Note(note, info.source + head + info.layout);
  for (const auto& w : info.warnings) Note(note, "warning: " + info.source + ": " + w);
}

// Samples after the last whole segment are not used: say so.
void NoteDropped(const EstimateNote& note, const std::string& path, size_t n_samples, const ident::WelchOptions& o) {
  const size_t n = o.window_length, step = n - o.overlap_samples();
  if (n_samples < n) return;  // Welch refuses it with a message
  const size_t segments = (n_samples - n) / step + 1;
  const size_t dropped = n_samples - ((segments - 1) * step + n);
  if (dropped == 0) return;
  char s[400];
  std::snprintf(s, sizeof s,
                ": the last %zu samples (%.1f %% of the log) do not fill a %zu-sample segment and are not used; a "
                "WelchOptions::window_length that fits, or LogsEstimateOptions::whole_record for a sweep or periodic "
                "excitation, uses them",
                dropped, 100.0 * dropped / n_samples, n);
  Note(note, "warning: " + path + s);
}

// whole_record, period_samples and the Welch window length that do not go together.
void CheckRecordOptions(const LogsEstimateOptions& o, const EstimateNote& note) {
  if (o.whole_record && o.welch.window_length != 0) {
    throw InputError("LogsEstimateOptions::whole_record takes each log (or LogsEstimateOptions::period_samples) as "
                     "one segment: drop WelchOptions::window_length");
  }
  if (o.period_samples != 0 && (!o.whole_record || o.period_samples < 16)) {
    throw InputError("LogsEstimateOptions::period_samples " + std::to_string(o.period_samples) +
                     ": needs LogsEstimateOptions::whole_record and a period of at least 16 samples");
  }
  if (o.whole_record && o.welch.detrend == ident::Detrend::kLinear) {
    Note(note,
         "warning: WelchOptions::detrend linear with LogsEstimateOptions::whole_record: each rectangular segment (a "
         "whole record or period) loses its straight-line fit, and for a periodic response that fit is not a drift "
         "but part of the signal (a rigid body's slow swing): it leaks into every bin and biases |H| most where it "
         "is small; WelchOptions::detrend mean (the LogsEstimateOptions::whole_record default) or none avoids it");
  }
}

// Closed loop: the selector that reads the logged excitation r as the "input".
io::LogSelect ExcitationSelect(const std::string& path, const LogsEstimateOptions& o) {
  io::LogSelect rsel = o.select;
  const bool h5 = io::DetectLogFormat(path) == io::LogFormat::kHdf5;
  if (h5 && o.reference_dataset.empty()) {
    throw InputError(path + ": an HDF5 log: name the excitation with LogsEstimateOptions::reference_dataset (not "
                     "LogsEstimateOptions::reference_column)");
  }
  if (!h5 && o.reference_column.empty()) {
    throw InputError(path + ": not an HDF5 log: name the excitation with LogsEstimateOptions::reference_column (not "
                     "LogsEstimateOptions::reference_dataset)");
  }
  if (h5) rsel.input_dataset = o.reference_dataset;
  else rsel.input_column = o.reference_column;
  return rsel;
}

// Open loop in Welch segments: one streaming pass, memory for a few windows.
// The default window (window_length 0) needs the log's rate and length, known
// at its end: the first kAutoWindowBuffer samples are held until then; a longer
// log is estimated with the window of its rate at 1 kHz (4096) as it streams,
// and read a second time when its rate asks for another one.
ident::RunSpectra StreamedRun(const std::string& path, const LogsEstimateOptions& opts, const EstimateNote& note,
                              io::LogInfo* info, std::uint64_t* fingerprint) {
  constexpr size_t kAutoWindowBuffer = size_t{1} << 17;  // 2 MiB of samples
  ident::WelchOptions o = opts.welch;
  const bool auto_window = o.window_length == 0;
  std::vector<double> held_u, held_y;
  if (auto_window) held_u.reserve(kAutoWindowBuffer), held_y.reserve(kAutoWindowBuffer);
  std::unique_ptr<ident::WelchEstimator> est;
  if (!auto_window) est = std::make_unique<ident::WelchEstimator>(o);
  io::LogFingerprint fp;
  *info = io::StreamLog(path, opts.select, [&](const double* u, const double* y, size_t n) {
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
  NoteRead(note, *info);
  {
    ident::WelchOptions resolved = o;
    if (auto_window) resolved.window_length = ident::DefaultWindowLength(info->sample_rate_hz, info->num_samples);
    CheckLogLength(info->num_samples, info->sample_rate_hz, resolved, auto_window);
  }
  if (auto_window) {
    const int want = ident::DefaultWindowLength(info->sample_rate_hz, info->num_samples);
    if (!est || want != o.window_length) {
      o.window_length = want;
      est = std::make_unique<ident::WelchEstimator>(o);
      if (!held_u.empty()) est->Push(held_u.data(), held_y.data(), held_u.size());
      else io::StreamLog(path, opts.select, [&](const double* u, const double* y, size_t n) { est->Push(u, y, n); });
    }
  }
  NoteDropped(note, path, info->num_samples, o);
  ident::RunSpectra spectra;
  spectra.uy = est->Finish(info->sample_rate_hz);
  return spectra;
}

// Each whole period of P samples one run of its own: the std is the scatter between periods.
std::vector<ident::RunSpectra> PeriodRuns(const std::string& path, const io::Log& log, const std::vector<double>& r,
                                          size_t P, ident::WelchOptions w, const EstimateNote& note) {
  const size_t periods = log.input.size() / P;
  if (periods == 0) {
    throw InputError("the log has " + std::to_string(log.input.size()) + " samples, fewer than one period of " +
                     std::to_string(P) + " (LogsEstimateOptions::period_samples)");
  }
  w.window_length = static_cast<int>(P);
  w.overlap = 0.0;
  w.window = ident::Window::kRect;
  NoteDropped(note, path, log.info.num_samples, w);
  std::vector<ident::RunSpectra> runs;
  for (size_t q = 0; q < periods; ++q) {
    auto cut = [&](const std::vector<double>& v) {
      return v.empty() ? v : std::vector<double>(v.begin() + q * P, v.begin() + (q + 1) * P);
    };
    runs.push_back(ident::EstimateRun(cut(log.input), cut(log.output), cut(r), log.info.sample_rate_hz, w));
  }
  return runs;
}

// The log in memory (closed loop, or whole_record): its run, or one run per
// period with period_samples.
std::vector<ident::RunSpectra> InMemoryRuns(const std::string& path, const LogsEstimateOptions& o,
                                            const EstimateNote& note, io::LogInfo* info, std::uint64_t* fingerprint) {
  io::Log log = io::ReadLog(path, o.select);
  *info = log.info;
  io::LogFingerprint fp;
  fp.Add(log.input.data(), log.output.data(), log.input.size());
  *fingerprint = fp.value();
  NoteRead(note, *info);
  std::vector<double> r;
  if (o.ClosedLoop()) {
    io::Log ex = io::ReadLog(path, ExcitationSelect(path, o));
    if (ex.input.size() != log.input.size()) {
      throw InputError("the excitation has " + std::to_string(ex.input.size()) + " samples, the input " +
                       std::to_string(log.input.size()));
    }
    r = std::move(ex.input);
  }
  if (o.whole_record && o.period_samples > 0) {
    return PeriodRuns(path, log, r, static_cast<size_t>(o.period_samples), o.welch, note);
  }
  ident::WelchOptions w = o.welch;
  const bool default_window = w.window_length == 0;
  if (default_window) w.window_length = ident::DefaultWindowLength(info->sample_rate_hz, info->num_samples);
  if (!o.whole_record) CheckLogLength(info->num_samples, info->sample_rate_hz, w, default_window);
  if (o.whole_record) {
    if (log.input.size() > (1u << 24)) throw InputError("a whole record is limited to 2^24 samples");
    w.window_length = static_cast<int>(log.input.size());
    w.overlap = 0.0;
    w.window = ident::Window::kRect;
  } else {
    NoteDropped(note, path, info->num_samples, w);
  }
  std::vector<ident::RunSpectra> runs;
  runs.push_back(ident::EstimateRun(log.input, log.output, r, info->sample_rate_hz, w));
  return runs;
}

// An InputError names the file first.
template <class F>
auto NamingTheFile(const std::string& path, F&& f) {
  try {
    return f();
  } catch (const InputError& e) {
    const std::string what = e.what();
    throw InputError(what.rfind(path, 0) == 0 ? what : path + ": " + what);
  }
}

// One log's runs.
std::vector<ident::RunSpectra> LogRuns(const std::string& path, const LogsEstimateOptions& o, const EstimateNote& note,
                                       io::LogInfo* info, std::uint64_t* fingerprint) {
  return NamingTheFile(path, [&] {
    if (o.ClosedLoop()) ExcitationSelect(path, o);  // the format and the excitation's name agree, before reading
    if (!o.ClosedLoop() && !o.whole_record) {
      return std::vector<ident::RunSpectra>{StreamedRun(path, o, note, info, fingerprint)};
    }
    return InMemoryRuns(path, o, note, info, fingerprint);
  });
}

// "<method> from N runs, M segments[; median coherences]".
std::string CombinedLine(const ident::CombinedResponse& r) {
  char s[300];
  std::snprintf(s, sizeof s, "%s from %d run%s, %d segments", ident::ToString(r.method).c_str(), r.num_runs,
                r.num_runs > 1 ? "s" : "", r.frf.num_averages);
  std::string line = s;
  if (r.method == ident::CombinedMethod::kJoint) {
    auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    std::snprintf(s, sizeof s, "; median coherence r->u %.3f, r->y %.3f (the coherence column holds r->y)",
                  median(r.coherence_ru), median(r.coherence_ry));
    line += s;
  }
  return line;
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

// Every log read whole (with its excitation in closed loop), one record
// each, of one rate (returned in *rate); out gets the infos and sample count.
std::vector<ident::LocalRecord> WholeRecords(const std::vector<std::string>& paths, const LogsEstimateOptions& options,
                                             const EstimateNote& note, LogsEstimate* out, double* rate) {
  std::vector<ident::LocalRecord> runs;
  std::vector<std::uint64_t> seen;
  *rate = 0.0;
  for (const std::string& path : paths) {
    NamingTheFile(path, [&] {
      io::Log log = io::ReadLog(path, options.select);
      NoteRead(note, log.info);
      io::LogFingerprint fp;
      fp.Add(log.input.data(), log.output.data(), log.input.size());
      RefuseRepeatedLog(paths, seen, fp.value(), path);
      seen.push_back(fp.value());
      ident::LocalRecord run{std::move(log.input), std::move(log.output), {}};
      if (options.ClosedLoop()) run.r = std::move(io::ReadLog(path, ExcitationSelect(path, options)).input);
      if (*rate == 0.0) *rate = log.info.sample_rate_hz;
      if (std::abs(log.info.sample_rate_hz - *rate) > 1e-3 * *rate) {
        throw InputError("the log's rate differs from the first log's: runs of one estimate need one rate");
      }
      out->total_samples += log.info.num_samples;
      out->infos.push_back(log.info);
      runs.push_back(std::move(run));
      return 0;
    });
  }
  return runs;
}

// The Welch options that a whole-record method (local, robust) does not take.
bool WelchSegmentsGiven(const LogsEstimateOptions& options) {
  return options.whole_record || options.welch.window_length != 0 ||
         options.welch.overlap != ident::WelchOptions{}.overlap;
}

// The local method: every log read whole (with its excitation in closed
// loop), one local estimate over all of them.
LogsEstimate EstimateLocal(const std::vector<std::string>& paths, const LogsEstimateOptions& options,
                           const EstimateNote& note) {
  const ident::LocalModelOptions& o = *options.local;
  if (options.period_samples != 0 || WelchSegmentsGiven(options)) {
    throw InputError("the local method (" + ident::ToString(o.method) +
                     ") fits a local model on each whole log: drop LogsEstimateOptions::whole_record, "
                     "LogsEstimateOptions::period_samples, WelchOptions::window_length and WelchOptions::overlap "
                     "(Welch options)");
  }
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  LogsEstimate out;
  double rate = 0.0;
  const std::vector<ident::LocalRecord> runs = WholeRecords(paths, options, note, &out, &rate);
  ident::LocalEstimate est = ident::EstimateLocal(runs, rate, o);
  for (const std::string& w : est.warnings) Note(note, "warning: " + w);
  out.response = ident::ToCombined(std::move(est), o.method, static_cast<int>(runs.size()));
  char s[300];
  std::snprintf(s, sizeof s, "%s (%s) from %zu run%s, %d bins per local window, %d residual degrees of freedom",
                ident::ToString(out.response.method).c_str(), out.response.frf.estimator.c_str(), runs.size(),
                runs.size() > 1 ? "s" : "", 2 * o.HalfWidth() + 1, out.response.frf.num_averages);
  Note(note, s);
  return out;
}

// The robust method: each log one realisation of a periodic excitation.
LogsEstimate EstimateRobustLogs(const std::vector<std::string>& paths, const LogsEstimateOptions& options,
                                const EstimateNote& note) {
  const ident::RobustOptions& o = *options.robust;
  if (options.local || options.ClosedLoop() || WelchSegmentsGiven(options)) {
    throw InputError("the robust method takes the periods of each whole log (one random-phase realisation per log, "
                     "open loop): drop LogsEstimateOptions::whole_record, WelchOptions::window_length, "
                     "WelchOptions::overlap, LogsEstimateOptions::reference_column/reference_dataset and the local "
                     "method's options");
  }
  LogsEstimate out;
  double rate = 0.0;
  const std::vector<ident::LocalRecord> runs = WholeRecords(paths, options, note, &out, &rate);
  const ident::RobustEstimate est = ident::EstimateRobust(runs, rate, o);
  char s[400];
  std::snprintf(s, sizeof s,
                "robust method from %d realisation%s of %d periods of %d samples (%d transient dropped), %zu excited "
                "lines%s",
                est.num_realisations, est.num_realisations > 1 ? "s" : "", est.num_periods, est.period_samples,
                o.transient_periods, est.f_hz.size(),
                est.num_realisations > 1 ? "" : "; with one realisation the nonlinear distortion is not known "
                                                "(record several random-phase realisations, one log each)");
  out.response = ident::ToCombined(est);
  Note(note, s);
  return out;
}

}  // namespace

void CheckLogLength(size_t num_samples, double rate_hz, const ident::WelchOptions& o, bool default_window) {
  const size_t n = static_cast<size_t>(o.window_length), step = n - o.overlap_samples();
  const size_t segments = default_window ? 3 : 1;
  const size_t need = n + (segments - 1) * step;
  if (num_samples >= need) return;
  const double T = model::SamplePeriod(rate_hz);
  char s[700];
  if (default_window) {
    // The overlap given (--overlap 0 was reported "at 50 % overlap" beside a count made with 0).
    ident::WelchOptions d = o;
    d.window_length = ident::DefaultWindowLength(rate_hz, size_t{1} << 40);
    const size_t nd = static_cast<size_t>(d.window_length), need_d = nd + 2 * (nd - d.overlap_samples());
    std::snprintf(s, sizeof s,
                  "the log is too short: %zu samples (%.3g s at %g Hz); an estimate needs 3 Welch segments of at "
                  "least %zu samples (%.3g s, the shortest default window at this rate: bins of %.3g Hz) at %.3g %% "
                  "overlap, so at least %zu samples (%.3g s). Record a longer log: at least %.3g s, and %.3g s or "
                  "more for the default %zu-sample window (bins of %.3g Hz)",
                  num_samples, num_samples * T, rate_hz, n, n * T, rate_hz / n, 100.0 * o.overlap, need, need * T,
                  need * T, need_d * T, nd, rate_hz / nd);
  } else {
    // The longest power-of-two windows that fit: one segment, and three.
    size_t one = 16, three = 16;
    while (one * 2 <= num_samples) one *= 2;
    while (three * 4 <= num_samples) three *= 2;
    std::string shorter = "record a longer log";
    if (num_samples >= 16) {
      shorter = "use WelchOptions::window_length " + std::to_string(one) + " or less";
      if (num_samples >= 32) shorter += " (" + std::to_string(three) + " or less for the 3 segments a per-bin std needs)";
    }
    std::snprintf(s, sizeof s,
                  "the log is too short: %zu samples (%.3g s at %g Hz), fewer than one window of %zu samples "
                  "(WelchOptions::window_length, %.3g s): record a longer log (at least %zu samples, %.3g s; %zu "
                  "samples, %.3g s, for the 3 segments a per-bin std needs), or %s",
                  num_samples, num_samples * T, rate_hz, n, n * T, n, n * T, n + 2 * step, (n + 2 * step) * T,
                  shorter.c_str());
  }
  throw InputError(s);
}

void ChooseRobust(LogsEstimateOptions* o, bool robust, int transient_periods) {
  if (!robust) {
    if (transient_periods != ident::RobustOptions{}.transient_periods) {
      throw InputError("RobustOptions::transient_periods is for the robust method of a periodic excitation");
    }
    return;
  }
  ident::RobustOptions r;
  r.period_samples = o->period_samples;
  r.transient_periods = transient_periods;
  r.fmin_hz = o->welch.fmin_hz;
  r.fmax_hz = o->welch.fmax_hz;
  std::string why;
  if (!r.IsValid(&why)) throw InputError(why);
  o->robust = r;
  o->period_samples = 0;  // the robust method's, not the Welch periods'
}

LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const LogsEstimateOptions& given,
                              const EstimateNote& note) {
  LogsEstimateOptions options = given;
  if (paths.empty()) throw InputError("no log to estimate from: give at least one");
  LogsEstimate out;
  if (options.robust) {
    out = EstimateRobustLogs(paths, options, note);
  } else if (options.local) {
    out = EstimateLocal(paths, options, note);
  } else {
    std::string why;
    ident::WelchOptions check = options.welch;
    if (check.window_length == 0) check.window_length = ident::WelchOptions{}.window_length;  // resolved per log
    if (!check.IsValid(&why)) throw InputError(why);
    CheckRecordOptions(options, note);
    // One segment: the per-bin std (the scatter between segments) would be infinite.
    auto one_segment = [&] {
      return InputError(std::string("LogsEstimateOptions::whole_record with one log and ") +
                        (options.period_samples > 0 ? "one whole period of LogsEstimateOptions::period_samples"
                                                    : "no LogsEstimateOptions::period_samples") +
                        " gives one segment: " +
                        (options.for_fit ? "no per-bin std to weight the fit"
                                         : "no scatter to estimate the per-bin std from") +
                        "; pass several runs of the same excitation, LogsEstimateOptions::period_samples for a "
                        "periodic one, or drop LogsEstimateOptions::whole_record (Welch segments)");
    };
    if (options.whole_record && options.period_samples == 0 && paths.size() < 2) throw one_segment();  // before reading
    std::vector<ident::RunSpectra> runs;
    std::vector<std::uint64_t> seen;  // one fingerprint per log read
    for (const std::string& path : paths) {
      io::LogInfo info;
      std::uint64_t fingerprint = 0;
      for (ident::RunSpectra& run : LogRuns(path, options, note, &info, &fingerprint)) runs.push_back(std::move(run));
      // The default window, resolved on the first log, is every run's (runs combine alike).
      if (options.welch.window_length == 0 && !runs.empty()) options.welch.window_length = runs.front().uy.window_length;
      RefuseRepeatedLog(paths, seen, fingerprint, path);
      seen.push_back(fingerprint);
      out.total_samples += info.num_samples;
      out.infos.push_back(info);
    }
    out.response = ident::CombineRuns(runs, options.welch.estimator,
                                      options.whole_record ? ident::StdSource::kRunScatter : ident::StdSource::kCoherence);
    if (options.whole_record && runs.size() < 2) throw one_segment();
    Note(note, CombinedLine(out.response));
  }
  // The stage named: estimate, before fit or write. Bins without input power
  // first (H is 0/0 there), then any other non-finite value.
  io::CheckInputPower(out.response.frf, JoinPaths(paths));
  io::CheckFiniteResponse(out.response.frf, JoinPaths(paths));
  return out;
}

}  // namespace zwidth::analysis
