// zwidth.fit and zwidth.FitResult (fit/fit.h).
//
#include <algorithm>

#include "analysis/fit_model_file.h"
#include "analysis/logs_estimate.h"
#include "fit/fit.h"
#include "io/fit_file.h"
#include "io/atomic_file.h"
#include "io/option_names.h"
#include "model/error.h"
#include "python/bind_common.h"
#include "stability/uncertainty.h"

namespace zwidth::python {
namespace {

struct PyFitResult {
  fit::FitResult result;
  io::ModelFile model;  // the fitted plant with its std and sample period
};

// The fit's texts in the module's keywords (io::WithKeywords).
void InKeywords(fit::FitResult* r) {
  for (std::string& w : r->warnings) w = io::WithKeywords(w);
  for (fit::QualityReason& q : r->reasons) {
    q.message = io::WithKeywords(q.message);
    q.advice = io::WithKeywords(q.advice);
  }
  r->order_choice = io::WithKeywords(r->order_choice);
  r->delay_choice = io::WithKeywords(r->delay_choice);
}

// The fit as `zwidth fit` makes it, by the same library function
// (analysis::FitToModelFile: Ceres and glog quiet, the sign / swapped-columns
// diagnosis, the friction fit of `friction`, the model file), every text in
// the keywords; the warnings are raised as UserWarning after the call. A fit
// that does not converge is returned with its status (the CLI exits 1).
PyFitResult FitAsCli(const ident::FrequencyResponse& frf, const fit::FitOptions& o, const std::string& name,
                     bool linear, const std::optional<analysis::FrictionInput>& friction,
                     std::vector<std::string> warnings) {
  PyFitResult out;
  fit::FrictionFitResult ff;
  analysis::FitMessages messages{.words = io::WithKeywords,
                                 .warning = [&](const std::string& w) { warnings.push_back(io::WithKeywords(w)); },
                                 .linear = linear};
  {
    py::gil_scoped_release release;
    ScopedCLocale c;
    TimedCpp([&] {
      try {
        out.model = analysis::FitToModelFile(frf, o, name, messages, &out.result, friction ? &*friction : nullptr, &ff);
      } catch (const ComputationError&) {
        if (out.result.status == fit::FitStatus::kConverged || out.result.status == fit::FitStatus::kNotRun) throw;
        out.model = io::FittedModelFile(out.result, frf, o, name);  // returned with its status, as before
      }
    });
  }
  InKeywords(&out.result);
  out.model.plant.name = name;
  out.model.linear = linear;
  const py::object warn = py::module_::import("warnings").attr("warn");
  for (const std::string& w : warnings) warn(w, py::module_::import("builtins").attr("UserWarning"), 3);
  return out;
}

// units: 'rotary' or 'linear' (io::ParseUnitsWord, as --units); None: not given.
std::optional<bool> UnitsFrom(const std::optional<std::string>& units) {
  if (!units) return std::nullopt;
  return io::ParseUnitsWord(*units, "units");
}

// zwidth.fit of a FrequencyResponse, or of a Log's (`log`, whose samples the
// friction fit reads again, with `welch`: the options the response was
// estimated with, as `zwidth fit LOG` gives its Welch flags): the friction
// fit's input by the CLI's rule (analysis::FrictionInputFor; a response alone
// is a saved response's case).
PyFitResult FitResponse(const ident::FrequencyResponse& frf, const fit::FitOptions& o, const std::string& friction,
                        const std::optional<std::string>& units, const std::string& name, const PyLog* log,
                        const ident::WelchOptions& welch = {}) {
  const fit::FrictionModel fm = analysis::FrictionModelNamed(friction);
  const bool linear = UnitsFrom(units).value_or(false);  // no header to read: rotary unless given
  std::optional<analysis::FrictionInput> in;
  std::string warning;
  if (log) {
    io::Log l;
    l.info.source = log->source;
    l.info.sample_rate_hz = log->sample_rate_hz;
    l.info.num_samples = log->u.size();
    l.input = log->u;
    l.output = log->y;
    in = analysis::FrictionInputFor(std::move(l), welch, fm);
  } else {
    in = analysis::FrictionInputFor({}, true, {}, {}, fm, &warning);
  }
  std::vector<std::string> warnings;
  if (!warning.empty()) warnings.push_back(io::WithKeywords(warning));
  return FitAsCli(frf, o, name, linear, in, std::move(warnings));
}

// zwidth.fit of log files: `zwidth fit LOG...`'s steps, each the library's
// (FrictionInputFor before anything is read, EstimateFromLogs for a fit,
// FitToModelFile).
PyFitResult FitLogs(const py::object& paths, const analysis::LogsEstimateOptions& estimate, const fit::FitOptions& o,
                    const std::string& friction, const std::optional<std::string>& units, const std::string& name) {
  const std::vector<std::string> logs = PathsFrom(paths);
  if (logs.empty()) throw InputError("data: no log given: pass a log file's path (or several)");
  const fit::FrictionModel fm = analysis::FrictionModelNamed(friction);
  const std::optional<bool> units_given = UnitsFrom(units);
  analysis::LogsEstimateOptions eo = estimate;
  eo.for_fit = true;
  std::string warning;
  const std::optional<analysis::FrictionInput> in =
      analysis::FrictionInputFor(logs, false, eo.select, eo.welch, fm, &warning);
  std::vector<std::string> warnings;
  if (!warning.empty()) warnings.push_back(io::WithKeywords(warning));
  io::ForgetNotedInputs();  // each call is its own command (the provenance's inputs)
  analysis::LogsEstimate est;
  {
    py::gil_scoped_release release;
    ScopedCLocale c;
    est = analysis::EstimateFromLogs(logs, eo, [&](const std::string& line) {
      if (line.rfind("warning: ", 0) == 0) warnings.push_back(io::WithKeywords(line.substr(9)));
    });
  }
  // The headers' units unless given (the CLI's rule), refused before the fit as `zwidth fit`.
  const bool linear = io::LinearUnitsOf(units_given, est.infos, "ModelFile::linear");
  return FitAsCli(est.response.frf, o, name, linear, in, std::move(warnings));
}

fit::FitOptions OptionsFrom(const py::object& modes, int max_modes, const py::object& delay_samples,
                            int max_auto_delay, bool allow_short, double fmin, double fmax,
                            double min_input_power_ratio, double min_coherence,
                            std::optional<io::ModelFile> init, int max_starts, int max_iterations,
                            double min_damping_ratio, double max_pole_damping_ratio,
                            double max_zero_damping_ratio, double max_frequency_fraction,
                            double relative_std_floor, double function_tolerance) {
  fit::FitOptions o = fit::UserFitOptions();
  if (py::isinstance<py::str>(modes)) {
    const std::string s = modes.cast<std::string>();
    if (s != "auto") throw InputError("modes '" + s + "': expected 'auto' or an integer >= 0");
    o.auto_modes = true;
  } else {
    o.num_modes = Integer(modes, "modes");
    o.auto_modes = false;
  }
  o.max_modes = max_modes;
  if (py::isinstance<py::str>(delay_samples)) {
    const std::string s = delay_samples.cast<std::string>();
    if (s != "auto") throw InputError("delay_samples '" + s + "': expected 'auto' or an integer >= 0");
    o.auto_delay = true;
  } else {
    o.delay_samples = Integer(delay_samples, "delay_samples");
    o.auto_delay = false;
  }
  o.max_auto_delay = max_auto_delay;
  o.allow_few_averages = allow_short;
  o.band.fmin_hz = fmin;
  o.band.fmax_hz = fmax;
  o.band.min_input_power_ratio = min_input_power_ratio;
  o.band.min_coherence = min_coherence;
  if (init) o.init = init->plant;
  o.max_starts = max_starts;
  o.max_iterations = max_iterations;
  o.min_damping_ratio = min_damping_ratio;
  o.max_pole_damping_ratio = max_pole_damping_ratio;
  o.max_zero_damping_ratio = max_zero_damping_ratio;
  o.max_frequency_fraction = max_frequency_fraction;
  o.relative_std_floor = relative_std_floor;
  o.function_tolerance = function_tolerance;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(io::WithKeywords(why));
  return o;
}

// A plant (a fit's, or its std with +inf where unknown) as a picklable tuple and back.
py::tuple PlantState(const model::Plant& p) {
  std::vector<double> modes;
  for (const model::Mode& md : p.modes) modes.insert(modes.end(), {md.omega, md.c, md.v, md.d});
  return py::make_tuple(p.m, p.b, p.delay_samples, p.name, Bytes(modes));
}
model::Plant PlantFrom(const py::handle& h) {
  const py::tuple t = py::reinterpret_borrow<py::tuple>(h);
  model::Plant p;
  p.m = t[0].cast<double>();
  p.b = t[1].cast<double>();
  p.delay_samples = t[2].cast<int>();
  p.name = t[3].cast<std::string>();
  const std::vector<double> v = FromBytes<double>(t[4]);
  for (size_t i = 0; i + 3 < v.size(); i += 4) p.modes.push_back({v[i], v[i + 1], v[i + 2], v[i + 3]});
  return p;
}

// Everything a FitResult shows, as one tuple (pickling, copy and ==).
py::tuple FitState(const PyFitResult& p) {
  const fit::FitResult& r = p.result;
  py::list reasons;
  for (const auto& q : r.reasons) reasons.append(py::make_tuple(q.code, q.message, q.advice));
  const ident::ExcitedBand& b = r.band;
  return py::make_tuple(
      io::ModelToJson(p.model).dump(), static_cast<int>(r.status), r.message, PlantState(r.plant),
      PlantState(r.std_errors), r.covariance_ok, Bytes(r.log_covariance),
      py::make_tuple(r.cost, r.num_residuals, r.num_parameters, r.chi2_per_dof, r.nrmse_fit_percent,
                     r.worst_misfit_hz, r.std_scale, r.starts_tried, r.iterations, r.runs_z, r.band_sample_rate_hz),
      r.warnings,
      py::make_tuple(Bytes(b.used), b.num_used, b.num_outside, b.num_low_input, b.num_low_coherence,
                     b.input_power_known, b.f_lo_hz, b.f_hi_hz, b.reference_input_psd),
      static_cast<int>(r.quality), reasons, Bytes(r.misfit_band_hz), r.order_choice, r.delay_choice);
}

PyFitResult FitFrom(const py::tuple& t) {
  PyFitResult p;
  p.model = io::ParseModelJson(t[0].cast<std::string>(), "<pickle>");
  fit::FitResult& r = p.result;
  r.status = static_cast<fit::FitStatus>(t[1].cast<int>());
  r.message = t[2].cast<std::string>();
  r.plant = PlantFrom(t[3]);
  r.std_errors = PlantFrom(t[4]);
  r.covariance_ok = t[5].cast<bool>();
  r.log_covariance = FromBytes<double>(t[6]);
  const py::tuple n = t[7];
  r.cost = n[0].cast<double>();
  r.num_residuals = n[1].cast<int>();
  r.num_parameters = n[2].cast<int>();
  r.chi2_per_dof = n[3].cast<double>();
  r.nrmse_fit_percent = n[4].cast<double>();
  r.worst_misfit_hz = n[5].cast<double>();
  r.std_scale = n[6].cast<double>();
  r.starts_tried = n[7].cast<int>();
  r.iterations = n[8].cast<int>();
  r.runs_z = n[9].cast<double>();
  r.band_sample_rate_hz = n[10].cast<double>();
  r.warnings = t[8].cast<std::vector<std::string>>();
  const py::tuple b = t[9];
  r.band.used = FromBytes<char>(b[0]);
  r.band.num_used = b[1].cast<int>();
  r.band.num_outside = b[2].cast<int>();
  r.band.num_low_input = b[3].cast<int>();
  r.band.num_low_coherence = b[4].cast<int>();
  r.band.input_power_known = b[5].cast<bool>();
  r.band.f_lo_hz = b[6].cast<double>();
  r.band.f_hi_hz = b[7].cast<double>();
  r.band.reference_input_psd = b[8].cast<double>();
  r.quality = static_cast<fit::FitQuality>(t[10].cast<int>());
  for (const py::handle& q : t[11]) {
    const py::tuple qt = py::reinterpret_borrow<py::tuple>(q);
    r.reasons.push_back({qt[0].cast<std::string>(), qt[1].cast<std::string>(), qt[2].cast<std::string>()});
  }
  r.misfit_band_hz = FromBytes<double>(t[12]);
  r.order_choice = t[13].cast<std::string>();
  r.delay_choice = t[14].cast<std::string>();
  return p;
}

// "<zwidth.FitResult poor (chi2_per_dof, residual_runs): modes=2 delay_samples=1 chi2/dof=3.1 ...>"
std::string FitRepr(const PyFitResult& p) {
  const fit::FitResult& r = p.result;
  std::string s = "<zwidth.FitResult " + fit::ToString(r.quality);
  if (!r.reasons.empty()) {
    s += " (";
    for (size_t i = 0; i < r.reasons.size(); ++i) s += (i ? ", " : "") + r.reasons[i].code;
    s += ")";
  }
  s += ": " + fit::ToString(r.status) + ", modes=" + std::to_string(r.plant.modes.size()) +
       " delay_samples=" + std::to_string(p.model.plant.delay_samples) + " chi2/dof=" + G(r.chi2_per_dof) +
       " fit=" + G(r.nrmse_fit_percent) + "% m=" + G(r.plant.m) + " b=" + G(r.plant.b);
  if (r.band.num_used > 0) {
    s += ", " + std::to_string(r.band.num_used) + " bins used " + G(r.band.f_lo_hz) + "-" + G(r.band.f_hi_hz) + " Hz";
  }
  return s + ">";
}

// zwidth.FitResult: the outcome of a fit, read-only.
void BindFitResult(py::module_& m) {
  py::class_<PyFitResult> cls(m, "FitResult", "The outcome of zwidth.fit.");
  DefValue(cls, &FitState, &FitFrom);
  cls.def("__repr__", &FitRepr, kCLocale)
      .def_property_readonly("used", [](const PyFitResult& r) {
             py::array_t<bool> a(static_cast<py::ssize_t>(r.result.band.used.size()));
             std::transform(r.result.band.used.begin(), r.result.band.used.end(), a.mutable_data(),
                            [](char c) { return c != 0; });
             return a;
           },
           "bool mask, one per bin of the response fitted: True where the fit used the bin (input power and "
           "coherence enough, inside [fmin, fmax]); plot frf.f_hz[res.used]")
      .def_property_readonly("band", [](const PyFitResult& r) { return r.result.band.Describe(); },
                             "the band used and the bins left out, in words (as `zwidth fit` prints it)")
      .def_readonly("model", &PyFitResult::model, "the fitted Model (with std and sample_period_s)")
      .def_property_readonly("status", [](const PyFitResult& r) { return fit::ToString(r.result.status); },
                             "'converged' (the numbers can be used) or the reason they cannot")
      .def_property_readonly("converged",
                             [](const PyFitResult& r) { return r.result.status == fit::FitStatus::kConverged; })
      .def_property_readonly("message", [](const PyFitResult& r) { return r.result.message; })
      .def_property_readonly("chi2_per_dof", [](const PyFitResult& r) { return r.result.chi2_per_dof; },
                             "sum of squared weighted residuals / (residuals - parameters)")
      .def_property_readonly("nrmse_fit_percent", [](const PyFitResult& r) { return r.result.nrmse_fit_percent; },
                             "100 (1 - |H - G| / |H - mean H|), MATLAB compare's 'fit'")
      .def_property_readonly("worst_misfit_hz", [](const PyFitResult& r) { return r.result.worst_misfit_hz; })
      .def_property_readonly("std_scale", [](const PyFitResult& r) { return r.result.std_scale; })
      .def_property_readonly("covariance_ok", [](const PyFitResult& r) { return r.result.covariance_ok; })
      .def_property_readonly("cost", [](const PyFitResult& r) { return r.result.cost; })
      .def_property_readonly("num_residuals", [](const PyFitResult& r) { return r.result.num_residuals; })
      .def_property_readonly("num_parameters", [](const PyFitResult& r) { return r.result.num_parameters; })
      .def_property_readonly("starts_tried", [](const PyFitResult& r) { return r.result.starts_tried; })
      .def_property_readonly("iterations", [](const PyFitResult& r) { return r.result.iterations; })
      .def_property_readonly("warnings", [](const PyFitResult& r) { return r.result.warnings; })
      .def_property_readonly("quality", [](const PyFitResult& r) { return fit::ToString(r.result.quality); },
                             "the verdict: 'good' (no test failed) or 'poor' (see quality_reasons: do not "
                             "trust the Z-width); 'not judged' when the fit did not converge")
      .def_property_readonly("quality_reasons", [](const PyFitResult& r) { return JsonToPython(r.model.fit.at("quality_reasons")); },
                             "the failed tests: a list of dicts code (chi2_per_dof, residual_runs, misfit_band, "
                             "few_averages, parameter_at_bound, spurious_section, order_search_at_limit, "
                             "delay_search_at_limit), message (what was seen) and advice (what to try)")
      .def_property_readonly("covariance", [](const PyFitResult& r) { return SquareArray(r.result.log_covariance); },
                             "parameter covariance in log space (the least-squares sandwich with the bins' correlation measured "
                             "from the residuals: fit/bin_correlated_covariance.h), an (n, n) array ordered "
                             "as covariance_names; None when it could not be computed")
      .def_property_readonly("covariance_names",
                             [](const PyFitResult& r) { return stability::LogParameterNames(r.result.plant); },
                             "'m', 'b', then 'modes[i].omega', '.c', '.v', '.d' (each the log of the parameter)")
      .def_property_readonly("order_choice", [](const PyFitResult& r) { return r.result.order_choice; },
                             "why this order (modes='auto')")
      .def_property_readonly("order_table", [](const PyFitResult& r) { return JsonToPython(r.model.fit.at("order_table")); },
                             "modes='auto': one dict per order tried (modes, chi2_per_dof, bic, pole_hz, ...)")
      .def_property_readonly("delay_choice", [](const PyFitResult& r) { return r.result.delay_choice; })
      .def("brief_report", [](const PyFitResult& r) { return r.result.BriefReport(); },
           "One line, as `zwidth fit` prints it (the verdict is quality; repr() shows both).", kCLocale)
;
}

// fit()'s keywords (FitOptions' defaults), shared by zwidth.run (through _fit_options).
auto FitArgs() {
  const fit::FitOptions d = fit::UserFitOptions();  // the defaults of every keyword, as the CLI's
  return std::make_tuple(
        py::arg("modes") = d.auto_modes ? py::object(py::str("auto")) : py::object(py::int_(d.num_modes)),
        py::arg("max_modes") = d.max_modes,
        py::arg("delay_samples") = d.auto_delay ? py::object(py::str("auto")) : py::object(py::int_(d.delay_samples)),
        py::arg("max_auto_delay") = d.max_auto_delay,
        py::arg("allow_short") = d.allow_few_averages,
        py::arg("fmin") = d.band.fmin_hz, py::arg("fmax") = d.band.fmax_hz,
        py::arg("min_input_power_ratio") = d.band.min_input_power_ratio,
        py::arg("min_coherence") = d.band.min_coherence, py::arg("init") = py::none(),
        py::arg("max_starts") = d.max_starts,
        py::arg("max_iterations") = d.max_iterations,
        py::arg("min_damping_ratio") = d.min_damping_ratio,
        py::arg("max_pole_damping_ratio") = d.max_pole_damping_ratio,
        py::arg("max_zero_damping_ratio") = d.max_zero_damping_ratio,
        py::arg("max_frequency_fraction") = d.max_frequency_fraction,
        py::arg("relative_std_floor") = d.relative_std_floor,
        py::arg("function_tolerance") = d.function_tolerance);
}

// zwidth.fit: FitOptions from keywords (OptionsFrom), then FitResponse.
void BindFitFunction(py::module_& m) {
  DefWith(m, "fit",
        [](const ident::FrequencyResponse& frf, const py::object& modes, int max_modes, const py::object& delay_samples,
           int max_auto_delay, bool allow_short, double fmin, double fmax, double min_input_power_ratio,
           double min_coherence, std::optional<io::ModelFile> init, int max_starts, int max_iterations, double min_damping_ratio,
           double max_pole_damping_ratio, double max_zero_damping_ratio, double max_frequency_fraction,
           double relative_std_floor, double function_tolerance, const std::string& friction,
           const std::optional<std::string>& units, const std::string& name) {
          const fit::FitOptions o =
              OptionsFrom(modes, max_modes, delay_samples, max_auto_delay, allow_short, fmin, fmax,
                          min_input_power_ratio, min_coherence, std::move(init), max_starts, max_iterations,
                          min_damping_ratio, max_pole_damping_ratio, max_zero_damping_ratio,
                          max_frequency_fraction, relative_std_floor, function_tolerance);
          return FitResponse(frf, o, friction, units, name, nullptr);
        },
        std::tuple_cat(std::make_tuple(py::arg("frf")), FitArgs(),
                       std::make_tuple(py::arg("friction") = "auto", py::arg("units") = py::none(),
                                       py::arg("name") = "")),

        R"doc(Fits eq. (1) with `modes` sections to a FrequencyResponse as `zwidth fit`
does (Ceres; residual against the exact ZOH response weighted by the per-bin
std). modes: an integer >= 0 or 'auto' (0..max_modes, lowest BIC among the
orders without a spurious section, as --modes auto). delay_samples: an
integer >= 0 or 'auto' (0..max_auto_delay, best kept). Bins used: [fmin,
fmax] Hz where the input has power (min_input_power_ratio) and the coherence
>= min_coherence. A response of fewer than 3 Welch segments raises
InputError unless allow_short=True (then judged 'poor'). init: a Model tried
first. A fit that does not converge is returned with its status (check
.converged); check .quality ('good'/'poor') and .quality_reasons before
using the numbers; bad options raise InputError. friction: 'auto' (Coulomb
friction fitted when the log shows it), 'coulomb' (always fitted) or 'none'
(the linear fit; friction only detected), as `zwidth fit --friction`; it
needs one time-domain log (a Log or a log file's path), so a response alone
warns that friction was not checked ('coulomb' raises InputError). units:
'rotary' or 'linear' (the model's labels, as --units); None: what a log
file's header says (N m, rad: rotary; N, m: linear), else rotary. The
fit is `zwidth fit`'s (analysis::FitToModelFile): the same verdict, reasons,
friction and numbers, and nothing printed.)doc", kCLocale);
  // zwidth.fit of a Log (its samples read again by the friction fit) and of log files.
  m.def("_fit_response",
        [](const ident::FrequencyResponse& frf, const fit::FitOptions& o, const std::string& friction,
           const std::optional<std::string>& units, const std::string& name, const PyLog& log,
           const analysis::LogsEstimateOptions& estimate) {
          return FitResponse(frf, o, friction, units, name, &log, estimate.welch);
        },
        py::arg("frf"), py::arg("fit"), py::arg("friction"), py::arg("units"), py::arg("name"), py::arg("log"),
        py::arg("estimate"),
        "fit(log, ...)'s core: the response estimated from the Log, the Log for the friction fit with the "
        "Welch options of `estimate` (_estimate_logs_options: the ones the response was estimated with).",
        kCLocale);
  m.def("_fit_logs", &FitLogs, py::arg("paths"), py::arg("estimate"), py::arg("fit"), py::arg("friction"),
        py::arg("units"), py::arg("name"),
        "fit(path, ...)'s core: `zwidth fit LOG...` with the options made by _estimate_logs_options and "
        "_fit_options.", kCLocale);
}

}  // namespace

void BindFit(py::module_& m) {
  py::class_<fit::FitOptions>(m, "_FitOptions", "fit options (zwidth.run's, from _fit_options)");
  DefWith(m, "_fit_options", &OptionsFrom, FitArgs(), "fit()'s options from its keywords (for zwidth.run).", kCLocale);
  BindFitResult(m);
  BindFitFunction(m);
}

}  // namespace zwidth::python
