// zwidth.fit and zwidth.FitResult (fit/fit.h).
//
#include "fit/fit.h"
#include "io/fit_file.h"
#include "model/error.h"
#include "python/bind_common.h"
#include "stability/uncertainty.h"

namespace zwidth::python {
namespace {

struct PyFitResult {
  fit::FitResult result;
  io::ModelFile model;  // the fitted plant with its std and sample period
};

// The library's messages name option fields (FitOptions::allow_few_averages);
// here they name the keywords. Other fields are left as they are (the CLI's
// table of fields and flags is apps/common.cc).
std::string Keywords(std::string s) {
  for (auto [from, to] : {std::pair{"FitOptions::allow_few_averages", "allow_short=True"},
                          std::pair{"WelchOptions::window_length ", "window_length="},
                          std::pair{"FitOptions::auto_modes", "modes='auto'"},
                          std::pair{"FitOptions::auto_delay", "delay_samples='auto'"},
                          std::pair{"FitOptions::num_modes", "modes"}}) {
    for (size_t p = s.find(from); p != std::string::npos; p = s.find(from, p)) s.replace(p, std::string(from).size(), to);
  }
  return s;
}

PyFitResult RunFit(const ident::FrequencyResponse& frf, const fit::FitOptions& o, const std::string& name) {
  PyFitResult out;
  try {
    py::gil_scoped_release release;
    TimedCpp([&] { out.result = fit::FitModel(frf, o); });
  } catch (const InputError& e) {
    throw InputError(Keywords(e.what()));
  }
  const fit::FitResult& r = out.result;
  // The model as `zwidth fit` stores it (io::FittedModelFile), named by the caller.
  out.model = io::FittedModelFile(r, frf, o, name);
  out.model.plant.name = name;
  return out;
}

fit::FitOptions OptionsFrom(const py::object& modes, int max_modes, const py::object& delay_samples,
                            int max_auto_delay, bool allow_short, double fmin, double fmax,
                            double min_input_power_ratio, double min_coherence,
                            std::optional<io::ModelFile> init, int max_starts, int max_iterations,
                            double min_damping_ratio, double max_pole_damping_ratio,
                            double max_zero_damping_ratio, double max_frequency_fraction,
                            double relative_std_floor, double function_tolerance) {
  fit::FitOptions o;
  if (py::isinstance<py::str>(modes)) {
    const std::string s = modes.cast<std::string>();
    if (s != "auto") throw InputError("modes '" + s + "': expected 'auto' or an integer >= 0");
    o.auto_modes = true;
  } else {
    if (py::isinstance<py::bool_>(modes)) throw InputError("modes: expected 'auto' or an integer >= 0");
    o.num_modes = modes.cast<int>();
  }
  o.max_modes = max_modes;
  if (py::isinstance<py::str>(delay_samples)) {
    const std::string s = delay_samples.cast<std::string>();
    if (s != "auto") throw InputError("delay_samples '" + s + "': expected 'auto' or an integer >= 0");
    o.auto_delay = true;
  } else {
    o.delay_samples = delay_samples.cast<int>();
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
  if (!o.IsValid(&why)) throw InputError(why);
  return o;
}

// zwidth.FitResult: the outcome of a fit, read-only.
void BindFitResult(py::module_& m) {
  py::class_<PyFitResult>(m, "FitResult", "The outcome of zwidth.fit.")
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
           "One line, as `zwidth fit` prints it.")
      .def("__repr__", [](const PyFitResult& r) { return "<zwidth.FitResult " + r.result.BriefReport() + ">"; });
}

// zwidth.fit: FitOptions from keywords (OptionsFrom), then RunFit.
void BindFitFunction(py::module_& m) {
  const fit::FitOptions d;  // the defaults of every keyword
  m.def("fit",
        [](const ident::FrequencyResponse& frf, const py::object& modes, int max_modes, const py::object& delay_samples,
           int max_auto_delay, bool allow_short, double fmin, double fmax, double min_input_power_ratio,
           double min_coherence, std::optional<io::ModelFile> init, int max_starts, int max_iterations, double min_damping_ratio,
           double max_pole_damping_ratio, double max_zero_damping_ratio, double max_frequency_fraction,
           double relative_std_floor, double function_tolerance, const std::string& name) {
          const fit::FitOptions o =
              OptionsFrom(modes, max_modes, delay_samples, max_auto_delay, allow_short, fmin, fmax,
                          min_input_power_ratio, min_coherence, std::move(init), max_starts, max_iterations,
                          min_damping_ratio, max_pole_damping_ratio, max_zero_damping_ratio,
                          max_frequency_fraction, relative_std_floor, function_tolerance);
          return RunFit(frf, o, name);
        },
        py::arg("frf"), py::arg("modes") = d.num_modes,
        py::arg("max_modes") = d.max_modes, py::arg("delay_samples") = d.delay_samples,
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
        py::arg("function_tolerance") = d.function_tolerance, py::arg("name") = "",
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
using the numbers; bad options raise InputError.)doc");
}

}  // namespace

void BindFit(py::module_& m) {
  BindFitResult(m);
  BindFitFunction(m);
}

}  // namespace zwidth::python
