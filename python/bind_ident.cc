// Logs, the Welch estimate and frequency-response files: zwidth.read_log,
// zwidth.simulate, zwidth.estimate, zwidth.FrequencyResponse.
#include <cmath>
#include <optional>
#include <tuple>
#include <utility>

#include "analysis/logs_estimate.h"
#include "analysis/validate.h"
#include "ident/local_models.h"
#include "io/atomic_file.h"
#include "io/option_names.h"
#include "io/frf_file.h"
#include "io/log.h"
#include "io/provenance.h"
#include "model/error.h"
#include "model/simulate.h"
#include "python/bind_common.h"
#include "model/sample_period.h"

namespace zwidth::python {
namespace {

// The Welch keywords as options: the library's one parser (ident::ParseWelchOptions,
// as the CLI's EstimateFlags::Resolve); window_length 0 = ident::DefaultWindowLength.
ident::WelchOptions WelchFrom(int window_length, double overlap, const std::string& window,
                              const std::string& detrend, const std::string& estimator, double fmin,
                              double fmax) {
  ident::WelchOptions o;
  o.window_length = window_length;
  o.overlap = overlap;
  o.fmin_hz = fmin;
  o.fmax_hz = fmax;
  return ident::ParseWelchOptions(o, window, detrend, estimator);
}

ident::FrequencyResponse Estimate(const std::vector<double>& u, const std::vector<double>& y,
                                  double sample_rate_hz, const ident::WelchOptions& o) {
  ident::WelchOptions w = o;  // window_length 0: the CLI's rule of the rate and length
  const bool default_window = w.window_length == 0;
  if (default_window) w.window_length = ident::DefaultWindowLength(sample_rate_hz, u.size());
  analysis::CheckLogLength(u.size(), sample_rate_hz, w, default_window);  // the CLI's length rule
  py::gil_scoped_release release;
  // Pushed in one call: the estimator's result does not depend on how the
  // samples are chunked, so this equals the CLI's streaming pass.
  ident::WelchEstimator est(w);
  est.Push(u.data(), y.data(), u.size());
  ident::FrequencyResponse r = est.Finish(sample_rate_hz);
  io::CheckFiniteResponse(r, "the estimate");  // as the CLI's estimate of a file (analysis::EstimateFromLogs)
  return r;
}

// The local options of `--estimator lpm|lrm` (and --local-*), or nothing for
// Welch's h1/h2. As the CLI (apps/common.cc), a local estimate takes the
// whole record: the Welch segment keywords must keep their defaults.
struct LocalArgs {
  int half_width = ident::LocalModelOptions{}.half_width;
  int order = ident::LocalModelOptions{}.order;
  int denominator_order = ident::LocalModelOptions{}.denominator_order;
  int differences = ident::LocalModelOptions{}.differences;
};

std::optional<ident::LocalModelOptions> LocalFrom(const std::string& estimator, const ident::WelchOptions& welch,
                                                   const LocalArgs& a) {
  ident::LocalModelOptions o;
  if (!ident::FromString(estimator, &o.method)) return std::nullopt;
  if (welch.window_length != 0 || welch.overlap != ident::WelchOptions{}.overlap) {
    throw InputError("estimator='" + estimator + "' fits a local model on the whole log: drop window_length and "
                     "overlap (Welch keywords)");
  }
  o.half_width = a.half_width;
  o.order = a.order;
  o.denominator_order = a.denominator_order;
  o.differences = a.differences;
  o.fmin_hz = welch.fmin_hz;
  o.fmax_hz = welch.fmax_hz;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  return o;
}

// analysis::EstimateFromLogs (the CLI's estimate of log files), its warnings
// raised as UserWarning in this module's keywords.
ident::FrequencyResponse EstimateLogsWarned(const std::vector<std::string>& files,
                                            const analysis::LogsEstimateOptions& o) {
  std::vector<std::string> warnings;
  analysis::LogsEstimate e;
  {
    py::gil_scoped_release release;
    ScopedCLocale c;
    e = analysis::EstimateFromLogs(files, o, [&](const std::string& line) {
      if (line.rfind("warning: ", 0) == 0) warnings.push_back(io::WithKeywords(line.substr(9)));
    });
  }
  const py::object warn = py::module_::import("warnings").attr("warn");
  for (const std::string& w : warnings) warn(w, py::module_::import("builtins").attr("UserWarning"), 2);
  return std::move(e.response.frf);
}

// Welch's estimate, or the local one (one run, open loop) when `local` is set.
ident::FrequencyResponse EstimateEither(const std::vector<double>& u, const std::vector<double>& y,
                                        double sample_rate_hz, const ident::WelchOptions& o,
                                        const std::optional<ident::LocalModelOptions>& local) {
  io::CheckLogSamples(sample_rate_hz, u, y, "estimate");  // what the readers refuse in a log file
  if (!local) return Estimate(u, y, sample_rate_hz, o);
  py::gil_scoped_release release;
  ident::FrequencyResponse r = ident::EstimateLocal({{u, y, {}}}, sample_rate_hz, *local).frf;
  io::CheckFiniteResponse(r, "the estimate");
  return r;
}

constexpr const char* kWelchDoc = R"doc(
Welch-averaged frequency response y/u, as `zwidth estimate` computes it:
window_length samples per segment (>= 16), overlap fraction in [0, 1),
window 'hann' | 'hamming' | 'rect' (periodic), detrend 'none' | 'mean' |
'linear' per segment, estimator 'h1' (S_uy/S_uu) | 'h2' (S_yy/S_yu), and the
band [fmin, fmax] Hz kept (default fmax inf: up to Nyquist, as the CLI).
estimator 'lpm' | 'lrm': the local polynomial / rational method on the
whole record (docs/estimators.md), with local_half_width (0: the method's
default), local_order, local_denominator_order (LRM) and local_differences,
as --local-*; window_length and overlap must then keep their defaults.)doc";

// A LogSelect from read_log's and estimate's selector keywords.
io::LogSelect SelectFrom(const std::string& input_column, const std::string& output_column,
                         const std::string& time_column, const std::string& input_dataset,
                         const std::string& output_dataset, const std::string& time_dataset, double rate,
                         double input_scale, double output_scale, const std::string& time_unit,
                         const std::string& delimiter) {
  io::LogSelect s;
  s.input_scale = input_scale;
  s.output_scale = output_scale;
  s.time_unit = time_unit;
  s.delimiter = delimiter;
  s.input_column = input_column;
  s.output_column = output_column;
  s.time_column = time_column;
  s.input_dataset = input_dataset;
  s.output_dataset = output_dataset;
  s.time_dataset = time_dataset;
  s.sample_rate_hz = rate;
  return s;
}

// The keywords of the log selectors (CSV columns, HDF5 datasets) with the CLI's defaults.
auto SelectorArgs() {
  return std::make_tuple(py::arg("input_column") = "torque", py::arg("output_column") = "position",
                         py::arg("time_column") = "t", py::arg("input_dataset") = "/input/torque",
                         py::arg("output_dataset") = "/output/position", py::arg("time_dataset") = "/time",
                         py::arg("rate") = 0.0, py::arg("input_scale") = 1.0, py::arg("output_scale") = 1.0,
                         py::arg("time_unit") = "", py::arg("delimiter") = "");
}

// The keywords of the Welch options (WelchFrom) with WelchOptions' defaults.
auto WelchArgs() {
  const ident::WelchOptions d;
  return std::make_tuple(py::arg("window_length") = 0, py::arg("overlap") = d.overlap,
                         py::arg("window") = "hann", py::arg("detrend") = "linear", py::arg("estimator") = "h1",
                         py::arg("fmin") = d.fmin_hz, py::arg("fmax") = d.fmax_hz,
                         py::arg("local_half_width") = LocalArgs{}.half_width, py::arg("local_order") = LocalArgs{}.order,
                         py::arg("local_denominator_order") = LocalArgs{}.denominator_order,
                         py::arg("local_differences") = LocalArgs{}.differences);
}

// The checks of a log made in memory: what the CLI's readers refuse in a file
// (io::CheckLogSamples), so that a Log is never one that save() cannot write.
void CheckLog(const PyLog& l) {
  if (l.u.empty() && l.y.empty()) throw InputError("u and y are empty: a log needs samples");
  io::CheckLogSamples(l.sample_rate_hz, l.u, l.y, l.source.empty() ? "Log" : l.source);
}

std::string LogRepr(const PyLog& l) {
  return "<zwidth.Log " + std::to_string(l.u.size()) + " samples at " + G(l.sample_rate_hz) + " Hz (" +
         G(static_cast<double>(l.u.size()) / l.sample_rate_hz) + " s)" +
         (l.source.empty() ? "" : " from " + py::repr(py::str(l.source)).cast<std::string>()) + ">";
}

// zwidth.Log: a log in memory.
void BindLog(py::module_& m) {
  py::class_<PyLog> cls(m, "Log", "A device log: torque input u [N m], position output y [rad], uniformly sampled.");
  cls.def(py::init([](const py::object& u, const py::object& y, const py::object& sample_rate_hz) {
             PyLog l;
             l.u = Samples(u, "u");
             l.y = Samples(y, "y");
             l.sample_rate_hz = Number(sample_rate_hz, "sample_rate_hz");
             CheckLog(l);
             return l;
           }),
           py::arg("u"), py::arg("y"), py::arg("sample_rate_hz"),
           "u [N m] and y [rad]: 1-D arrays of finite numbers of the same length; sample_rate_hz [Hz] > 0.", kCLocale)
      .def_readonly("source", &PyLog::source, "the file it was read from ('' when made in memory)")
      .def_readonly("sample_rate_hz", &PyLog::sample_rate_hz, "[Hz]")
      .def_property_readonly("period_s", &PyLog::period_s, "the sample period T [s]")
      .def_property_readonly("num_samples", [](const PyLog& l) { return l.u.size(); })
      .def_property_readonly("t", [](const PyLog& l) {
        std::vector<double> t(l.u.size());
        for (size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) / l.sample_rate_hz;
        return ToArray(t);
      }, "sample times k / sample_rate_hz [s] (the readers check that the file's are uniform)")
      .def_property_readonly("u", [](const PyLog& l) { return ToArray(l.u); }, "input (torque) [N m]")
      .def_property_readonly("y", [](const PyLog& l) { return ToArray(l.y); }, "output (position) [rad]")
      .def("save", [](const PyLog& l, const py::object& p) {
             const std::string path = PathFrom(p, "path");
             CheckLog(l);
             ScopedCLocale c;
             io::ForgetNotedInputs();
             io::WriteLog(path, l.sample_rate_hz, l.u, l.y);
           },
           py::arg("path"),
           "Writes the log as CSV (t,torque,position; '.' decimals whatever the locale) or HDF5 by the "
           "extension (atomically).", kCLocale)
      .def("__len__", [](const PyLog& l) { return l.u.size(); }, kCLocale)
      .def("__repr__", &LogRepr, kCLocale);
  DefValue(cls, [](const PyLog& l) { return py::make_tuple(l.source, l.sample_rate_hz, Bytes(l.u), Bytes(l.y)); },
           [](const py::tuple& t) {
             PyLog l;
             l.source = t[0].cast<std::string>();
             l.sample_rate_hz = t[1].cast<double>();
             l.u = FromBytes<double>(t[2]);
             l.y = FromBytes<double>(t[3]);
             CheckLog(l);  // a state made by hand is checked as the constructor checks
             return l;
           });
}

// zwidth.read_log: a log file read with the CLI's selectors.
void BindReadLog(py::module_& m) {
  DefWith(m, "read_log",
        [](const py::object& p, const std::string& input_column, const std::string& output_column,
           const std::string& time_column, const std::string& input_dataset, const std::string& output_dataset,
           const std::string& time_dataset, double rate, double input_scale, double output_scale,
           const std::string& time_unit, const std::string& delimiter, double max_interval_deviation) {
          const std::string path = PathFrom(p, "path");
          io::LogSelect s = SelectFrom(input_column, output_column, time_column, input_dataset, output_dataset,
                                       time_dataset, rate, input_scale, output_scale, time_unit, delimiter);
          s.max_interval_deviation = max_interval_deviation;
          PyLog l;
          {
            py::gil_scoped_release release;
            ScopedCLocale c;
            io::Log log = io::ReadLog(path, s);
            l.source = log.info.source;
            l.sample_rate_hz = log.info.sample_rate_hz;
            l.u = std::move(log.input);
            l.y = std::move(log.output);
          }
          return l;
        },
        std::tuple_cat(std::make_tuple(py::arg("path")), SelectorArgs(),
                       std::make_tuple(py::arg("max_interval_deviation") = 0.01)),
        R"doc(Reads a log (text, HDF5 or .mat, by content) as `zwidth estimate` does,
with the CLI's selectors: text columns input_column, output_column,
time_column (a header name or a 1-based position as a string; time_column
"none" with rate); HDF5 datasets input_dataset, output_dataset, time_dataset;
rate [Hz] > 0 overrides the file's (--rate); input_scale, output_scale
multiply the signals (counts to rad, volts to N m: --input-scale,
--output-scale); time_unit "s" | "ms" | "us" ("" = s, a unit in the column's
name refused: --time-unit); delimiter "" (detected), ";", "\t", "," or " "
(--delimiter). Raises InputError naming the file, row or dataset.)doc", kCLocale);
}

// zwidth.FrequencyResponse: made, loaded, saved, read.
void BindFrequencyResponse(py::module_& m) {
  py::class_<ident::FrequencyResponse> cls(m, "FrequencyResponse",
                                       "An empirical frequency response (output/input) with its coherence and "
                                       "per-bin standard deviation, as `zwidth estimate` writes it.");
  cls.def(py::init([](const py::object& f_hz, const py::object& H, const py::object& sample_rate_hz,
                       const py::object& coherence, const py::object& H_std, const py::object& num_averages) {
             ident::FrequencyResponse r;
             r.f_hz = Samples(f_hz, "f_hz");
             r.H = ComplexSamples(H, "H");
             r.sample_rate_hz = Number(sample_rate_hz, "sample_rate_hz");
             r.num_averages = Integer(num_averages, "num_averages");
             r.effective_averages = r.num_averages;
             const size_t n = r.f_hz.size();
             // The defaults of a response file without these columns (io/frf_file.h).
             r.coherence = coherence.is_none() ? std::vector<double>(n, 1.0) : Samples(coherence, "coherence");
             if (!H_std.is_none()) {
               r.H_std = Samples(H_std, "H_std");
             } else {
               for (const auto& h : r.H) r.H_std.push_back(std::abs(h) * 1e-3);
             }
             io::CheckResponseValues(r, "FrequencyResponse");
             // No spectra: zeros, as the reader gives a file without them (input power unknown).
             r.S_uu.assign(n, 0.0);
             r.S_yy.assign(n, 0.0);
             r.S_uy.assign(n, 0.0);
             return r;
           }),
           py::arg("f_hz"), py::arg("H"), py::arg("sample_rate_hz"), py::arg("coherence") = py::none(),
           py::arg("H_std") = py::none(), py::arg("num_averages") = 1,
           "A response measured elsewhere: f_hz [Hz] increasing, below Nyquist (sample_rate_hz / 2); "
           "complex H; missing coherence is 1 and H_std |H| 1e-3 (equal relative weights), "
           "as for a response file without those columns.", kCLocale)
      .def_static("load", [](const py::object& p, double sample_rate_hz) {
                    const std::string path = PathFrom(p, "path");
                    py::gil_scoped_release release;
                    ScopedCLocale c;
                    return io::ReadFrequencyResponse(path, sample_rate_hz);
                  },
                  py::arg("path"), py::arg("sample_rate_hz") = 0.0,
                  "Reads a response file of `zwidth estimate` (CSV or HDF5).", kCLocale)
      .def("save", [](const ident::FrequencyResponse& r, const py::object& p) {
             const std::string path = PathFrom(p, "path");
             io::CheckResponseValues(r, "FrequencyResponse");  // never a file the reader refuses
             ScopedCLocale c;
             io::ForgetNotedInputs();  // each call is its own command
             io::WriteFrequencyResponse(path, r);
           },
           py::arg("path"), "Writes it as `zwidth estimate -o` does (CSV or HDF5 by extension).", kCLocale);
  cls.def_readonly("sample_rate_hz", &ident::FrequencyResponse::sample_rate_hz, "[Hz]")
      .def_property_readonly("period_s", &ident::FrequencyResponse::period_s,
                             "the sample period T [s] of the log it was estimated from")
      .def_readonly("window_length", &ident::FrequencyResponse::window_length, "samples per segment")
      .def_readonly("num_averages", &ident::FrequencyResponse::num_averages, "Welch segments averaged")
      .def_readonly("effective_averages", &ident::FrequencyResponse::effective_averages,
                    "equivalent independent averages (Welch 1967)")
      .def_readonly("bin_correlation", &ident::FrequencyResponse::bin_correlation)
      .def_property_readonly("f_hz", [](const ident::FrequencyResponse& r) { return ToArray(r.f_hz); }, "[Hz]")
      .def_property_readonly("H", [](const ident::FrequencyResponse& r) { return ToArray(r.H); },
                             "complex output/input, e.g. rad/(N m)")
      .def_property_readonly("coherence", [](const ident::FrequencyResponse& r) { return ToArray(r.coherence); },
                             "magnitude-squared, [0, 1]")
      .def_property_readonly("H_std", [](const ident::FrequencyResponse& r) { return ToArray(r.H_std); },
                             "per-bin standard deviation of H (Bendat & Piersol)")
      .def_property_readonly("S_uu", [](const ident::FrequencyResponse& r) { return ToArray(r.S_uu); })
      .def_property_readonly("S_yy", [](const ident::FrequencyResponse& r) { return ToArray(r.S_yy); })
      .def_property_readonly("S_uy", [](const ident::FrequencyResponse& r) { return ToArray(r.S_uy); })
      .def_readonly("estimator", &ident::FrequencyResponse::estimator,
                    "which estimator made H ('welch-h1', 'lpm', 'lrm', 'robust', ...; '' when unknown)")
      .def_property_readonly("noise_var", [](const ident::FrequencyResponse& r) { return ToArray(r.noise_var); },
                             "estimator='robust': per bin, the variance E|dH|^2 from the noise (else empty)")
      .def_property_readonly("distortion_var",
                             [](const ident::FrequencyResponse& r) { return ToArray(r.distortion_var); },
                             "estimator='robust' with several realisations: per bin, the variance from the "
                             "nonlinear distortions (else empty)")
      .def("__len__", [](const ident::FrequencyResponse& r) { return r.f_hz.size(); }, kCLocale)
      .def("__repr__", [](const ident::FrequencyResponse& r) {
        std::string s = "<zwidth.FrequencyResponse " + std::to_string(r.f_hz.size()) + " bins";
        if (!r.f_hz.empty()) s += " " + G(r.f_hz.front()) + "-" + G(r.f_hz.back()) + " Hz";
        s += ", " + std::to_string(r.num_averages) + " averages";
        if (r.num_averages < 3) s += " (fewer than 3: fit() refuses it without allow_short=True)";
        return s + ", sample_rate_hz=" + G(r.sample_rate_hz) + ">";
      }, kCLocale);
  DefValue(cls,
           [](const ident::FrequencyResponse& r) {
             return py::make_tuple(r.sample_rate_hz, r.window_length, r.num_averages, r.effective_averages,
                                   r.bin_correlation, Bytes(r.f_hz), Bytes(r.H), Bytes(r.coherence), Bytes(r.H_std),
                                   Bytes(r.S_uu), Bytes(r.S_yy), Bytes(r.S_uy), Bytes(r.used_by_fit));
           },
           [](const py::tuple& t) {
             ident::FrequencyResponse r;
             r.sample_rate_hz = t[0].cast<double>();
             r.window_length = t[1].cast<int>();
             r.num_averages = t[2].cast<int>();
             r.effective_averages = t[3].cast<double>();
             r.bin_correlation = t[4].cast<double>();
             r.f_hz = FromBytes<double>(t[5]);
             r.H = FromBytes<std::complex<double>>(t[6]);
             r.coherence = FromBytes<double>(t[7]);
             r.H_std = FromBytes<double>(t[8]);
             r.S_uu = FromBytes<double>(t[9]);
             r.S_yy = FromBytes<double>(t[10]);
             r.S_uy = FromBytes<std::complex<double>>(t[11]);
             r.used_by_fit = FromBytes<char>(t[12]);
             // A state made by hand: the reader's rules (never a response save() cannot write).
             io::CheckResponseValues(r, "FrequencyResponse state");
             const size_t n = r.f_hz.size();
             if (r.S_uu.size() != n || r.S_yy.size() != n || r.S_uy.size() != n ||
                 !(r.used_by_fit.empty() || r.used_by_fit.size() == n)) {
               throw InputError("FrequencyResponse state: the spectra or the used mask have another length than "
                                "f_hz (" + std::to_string(n) + ")");
             }
             return r;
           });
}

// zwidth.estimate from a file (streamed), from arrays, from a Log.
void BindEstimate(py::module_& m) {
  DefWith(m, "estimate",
        [](const std::string& path, int window_length, double overlap, const std::string& window,
           const std::string& detrend, const std::string& estimator, double fmin, double fmax, int local_half_width,
           int local_order, int local_denominator_order, int local_differences, const std::string& input_column, const std::string& output_column, const std::string& time_column,
           const std::string& input_dataset, const std::string& output_dataset, const std::string& time_dataset,
           double rate, double input_scale, double output_scale, const std::string& time_unit,
           const std::string& delimiter) {
          const ident::WelchOptions o = WelchFrom(window_length, overlap, window, detrend, estimator, fmin, fmax);
          const io::LogSelect s = SelectFrom(input_column, output_column, time_column, input_dataset, output_dataset,
                                             time_dataset, rate, input_scale, output_scale, time_unit, delimiter);
          const auto local =
              LocalFrom(estimator, o, {local_half_width, local_order, local_denominator_order, local_differences});
          // The CLI's `zwidth estimate LOG` (analysis::EstimateFromLogs): Welch streamed
          // (a few windows in memory), the window of the log's rate and length by default.
          analysis::LogsEstimateOptions lo;
          lo.select = s;
          lo.welch = o;
          lo.local = local;
          return EstimateLogsWarned({CheckedPath(path, "path")}, lo);
        },
        std::tuple_cat(std::make_tuple(py::arg("path")), WelchArgs(), SelectorArgs()),
        "estimate(path, ...): streamed from a log file as `zwidth estimate` does (a few windows in memory, "
        "whatever the log's length), with read_log's selectors.", kCLocale);
  DefWith(m, "estimate",
        [](const py::object& u, const py::object& y, double sample_rate_hz, int window_length, double overlap,
           const std::string& window, const std::string& detrend, const std::string& estimator, double fmin,
           double fmax, int local_half_width, int local_order, int local_denominator_order, int local_differences) {
          const ident::WelchOptions o = WelchFrom(window_length, overlap, window, detrend, estimator, fmin, fmax);
          const auto local =
              LocalFrom(estimator, o, {local_half_width, local_order, local_denominator_order, local_differences});
          const std::vector<double> uv = Samples(u, "u");  // u's message first
          return EstimateEither(uv, Samples(y, "y"), sample_rate_hz, o, local);
        },
        std::tuple_cat(std::make_tuple(py::arg("u"), py::arg("y"), py::arg("sample_rate_hz")), WelchArgs()),
        kWelchDoc, kCLocale);
  DefWith(m, "estimate",
        [](const PyLog& log, int window_length, double overlap, const std::string& window,
           const std::string& detrend, const std::string& estimator, double fmin, double fmax, int local_half_width,
           int local_order, int local_denominator_order, int local_differences) {
          const ident::WelchOptions o = WelchFrom(window_length, overlap, window, detrend, estimator, fmin, fmax);
          const auto local =
              LocalFrom(estimator, o, {local_half_width, local_order, local_denominator_order, local_differences});
          try {
            return EstimateEither(log.u, log.y, log.sample_rate_hz, o, local);
          } catch (const InputError& e) {  // as the CLI: the file first
            if (log.source.empty()) throw;
            throw InputError(log.source + ": " + e.what());
          }
        },
        std::tuple_cat(std::make_tuple(py::arg("log")), WelchArgs()), "estimate(log, ...): the same from a Log.", kCLocale);
}

// estimate_logs()'s options from its keywords (the CLI's EstimateFlags::Options).
analysis::LogsEstimateOptions LogsOptionsFrom(int window_length, double overlap, const std::string& window,
                                              const std::optional<std::string>& detrend, const std::string& estimator,
                                              double fmin, double fmax, const std::string& reference_column,
                                              const std::string& reference_dataset, bool whole_record,
                                              int period_samples, int transient_periods,
                                              const std::string& input_column,
                                              const std::string& output_column, const std::string& time_column,
                                              const std::string& input_dataset, const std::string& output_dataset,
                                              const std::string& time_dataset, double rate, double input_scale,
                                              double output_scale, const std::string& time_unit,
                                              const std::string& delimiter) {
  analysis::LogsEstimateOptions o;
  const bool local = estimator == "lpm" || estimator == "lrm", robust = estimator == "robust";
  const std::string det = detrend ? *detrend : ident::ToString(analysis::DefaultDetrend(whole_record));
  // window_length 0: the library's default rule (the first log's rate and length), as the CLI.
  o.welch = WelchFrom(window_length, overlap, window, det, local || robust ? "h1" : estimator, fmin, fmax);
  if (local) {
    ident::LocalModelOptions lo;
    ident::FromString(estimator, &lo.method);
    lo.fmin_hz = fmin;
    lo.fmax_hz = fmax;
    o.local = lo;
  }
  o.select = SelectFrom(input_column, output_column, time_column, input_dataset, output_dataset,
                        time_dataset, rate, input_scale, output_scale, time_unit, delimiter);
  o.reference_column = reference_column;
  o.reference_dataset = reference_dataset;
  o.whole_record = whole_record;
  o.period_samples = period_samples;
  analysis::ChooseRobust(&o, robust, transient_periods);  // as the CLI (apps/common.cc)
  return o;
}

// zwidth.estimate_logs: several runs, whole records, periods, closed loop
// and the local methods, by the library's one estimate of logs
// (analysis::EstimateFromLogs, what `zwidth estimate/fit/run LOG...` use).
void BindEstimateLogs(py::module_& m) {
  const ident::WelchOptions d;
  py::class_<analysis::LogsEstimateOptions>(m, "_LogsEstimateOptions",
                                             "estimate options (estimate_logs' and run's, from _estimate_logs_options)");
  DefWith(m, "_estimate_logs_options", &LogsOptionsFrom,
          std::make_tuple(py::arg("window_length") = 0, py::arg("overlap") = d.overlap, py::arg("window") = "hann",
                        py::arg("detrend") = py::none(), py::arg("estimator") = "h1", py::arg("fmin") = d.fmin_hz,
                        py::arg("fmax") = d.fmax_hz, py::arg("reference_column") = "",
                        py::arg("reference_dataset") = "", py::arg("whole_record") = false,
                        py::arg("period_samples") = 0,
                        py::arg("transient_periods") = ident::RobustOptions{}.transient_periods,
                        py::arg("input_column") = "torque",
                        py::arg("output_column") = "position", py::arg("time_column") = "t",
                        py::arg("input_dataset") = "/input/torque", py::arg("output_dataset") = "/output/position",
                        py::arg("time_dataset") = "/time", py::arg("rate") = 0.0, py::arg("input_scale") = 1.0,
                        py::arg("output_scale") = 1.0, py::arg("time_unit") = "", py::arg("delimiter") = ""),
          R"doc(The frequency response of one device from one or several log files, as
`zwidth estimate LOG...` computes it (the same library function): runs
averaged (the same samples twice refused); window_length 0 (the default)
is the CLI's rule: the power of two nearest 4.096 s at the first log's rate,
halved until the log holds 3 segments; whole_record=True takes each log
as one rectangular segment, with period_samples one segment per period of a
periodic excitation (detrend default 'mean' then, else 'linear'); a closed
loop's logged excitation named by reference_column (text, .mat) or
reference_dataset (HDF5) gives H = S_ry / S_ru; estimator 'h1' | 'h2'
(Welch) | 'lpm' | 'lrm' (local methods on each whole log, in [fmin, fmax])
| 'robust' (a periodic excitation of period_samples, each log one
random-phase realisation, transient_periods dropped first: noise_var and
distortion_var per line, and the fit's verdict reads them).
Warnings (samples left out, ...) are raised as UserWarning; errors as
InputError naming the file.)doc", kCLocale);
  m.def("_estimate_logs", [](const py::object& paths, const analysis::LogsEstimateOptions& o) {
          const std::vector<std::string> files = PathsFrom(paths);
          if (files.empty()) throw InputError("paths: no log given: pass a log file's path (or several)");
          return EstimateLogsWarned(files, o);
        },
        py::arg("paths"), py::arg("options"), "estimate_logs(paths, **keywords) with the options made.", kCLocale);
}

// zwidth.simulate: a simulated log.
void BindSimulate(py::module_& m) {
  m.def("simulate",
        [](const io::ModelFile& model, double seconds, double sample_rate_hz, double torque_rms,
           double bandwidth_hz, double encoder_step_rad, double noise_std_rad, int delay_samples, uint64_t seed) {
          model::SimulateOptions o;
          o.seconds = seconds;
          o.sample_rate_hz = sample_rate_hz;
          o.torque_rms = torque_rms;
          o.bandwidth_hz = bandwidth_hz;
          o.encoder_step_rad = encoder_step_rad;
          o.noise_std_rad = noise_std_rad;
          o.delay_samples = delay_samples;
          o.seed = seed;
          PyLog l;
          {
            py::gil_scoped_release release;
            model::SimulatedLog s = model::SimulateLog(model.plant, o);
            l.sample_rate_hz = s.sample_rate_hz;
            l.u = std::move(s.torque);
            l.y = std::move(s.position);
          }
          CheckLog(l);  // as `zwidth simulate -o` refuses to write it (io::WriteLog)
          return l;
        },
        py::arg("model"), py::arg("seconds") = 30.0, py::arg("sample_rate_hz") = 1000.0,
        py::arg("torque_rms") = 0.03, py::arg("bandwidth_hz") = 300.0,
        py::arg("encoder_step_rad") = model::SimulateOptions{}.encoder_step_rad, py::arg("noise_std_rad") = 0.0,
        py::arg("delay_samples") = 0, py::arg("seed") = 1,
        R"doc(A simulated log as `zwidth simulate` makes it: band-limited white-noise
torque through the exact sampled plant, encoder quantisation (rad per count,
0 = none) and Gaussian sensor noise. Seeded: the same arguments give the
same samples.)doc", kCLocale);
}

}  // namespace

std::vector<std::string> PathsFrom(const py::object& paths) {
  std::vector<std::string> files;
  if (py::isinstance<py::str>(paths) || py::isinstance<py::bytes>(paths) || py::hasattr(paths, "__fspath__")) {
    files.push_back(PathFrom(paths, "paths"));
  } else {
    if (!py::hasattr(paths, "__iter__")) {
      throw py::type_error("paths: expected a path or a sequence of paths, not " +
                           py::str(py::type::of(paths).attr("__name__")).cast<std::string>());
    }
    for (const py::handle& p : paths) files.push_back(PathFrom(p, "paths"));
  }
  return files;
}

// zwidth.validate: a model on a log it was not fitted to (analysis/validate.h),
// as `zwidth validate MODEL LOG -o` reports it.
void BindValidate(py::module_& m) {
  const analysis::ValidateOptions d;
  m.def("validate",
        [](const io::ModelFile& model, const py::object& log, int max_lag, double relative_std_floor) {
          analysis::ValidateOptions o;
          o.max_lag = max_lag;
          o.relative_std_floor = relative_std_floor;
          io::Log l;
          if (!py::isinstance<PyLog>(log)) {
            const std::string path = PathFrom(log, "log");
            io::ForgetNotedInputs();  // each call is its own command (the provenance's inputs)
            py::gil_scoped_release release;
            ScopedCLocale c;
            l = io::ReadLog(path, io::LogSelect{});
          } else {
            const PyLog& p = log.cast<const PyLog&>();
            CheckLog(p);
            l.info.source = p.source;
            l.info.sample_rate_hz = p.sample_rate_hz;
            l.info.num_samples = p.u.size();
            l.input = p.u;
            l.output = p.y;
          }
          io::SetInvocation("zwidth.validate(" + (model.plant.name.empty() ? std::string("model") : model.plant.name) +
                            ", " + (l.info.source.empty() ? std::string("log") : l.info.source) + ")");
          nlohmann::ordered_json j;
          {
            py::gil_scoped_release release;
            j = analysis::ValidationToJson(analysis::Validate(model, l, o));
          }
          j["provenance"] = nlohmann::ordered_json::parse(io::ProvenanceJson().dump());
          return JsonToPython(nlohmann::json::parse(j.dump()));
        },
        py::arg("model"), py::arg("log"), py::arg("max_lag") = d.max_lag,
        py::arg("relative_std_floor") = d.relative_std_floor,
        R"doc(Checks a model on a log it was not fitted to, as `zwidth validate MODEL
LOG -o` does (MATLAB's compare and resid): log is a Log or a log file's path
(read with the default selectors; use read_log for others). Returns the dict
`zwidth validate -o` writes: quality 'good'/'poor' with quality_reasons and
reasons, fit_percent (the simulated output's NRMSE fit %), chi2_per_dof of the
fresh response against the model in units of its per-bin std with chi2_limit,
the residual's autocorrelation and cross-correlation with the input against
correlation_bound (99 %), warnings, and the provenance. Raises InputError for
a log of another rate than the model's or one too short.)doc", kCLocale);
}

void BindIdent(py::module_& m) {
  BindLog(m);
  BindValidate(m);
  BindReadLog(m);
  BindFrequencyResponse(m);
  BindEstimate(m);
  BindEstimateLogs(m);
  BindSimulate(m);
}

}  // namespace zwidth::python
