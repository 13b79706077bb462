// zwidth.Model: the plant of eq. (1) with its file-level extras (standard
// errors, sample period, fit metrics), i.e. io::ModelFile.
#include <cmath>
#include <numbers>

#include <pybind11/eigen.h>

#include "io/export.h"
#include "io/printable.h"
#include "io/provenance.h"
#include "io/reference_models.h"
#include "model/error.h"
#include "model/units.h"
#include "model/state_space.h"
#include "io/atomic_file.h"
#include "python/bind_common.h"
#include "stability/uncertainty.h"

namespace zwidth::python {
namespace {

using ModeTuple = std::tuple<double, double, double, double>;

std::vector<ModeTuple> ModesOf(const model::Plant& p) {
  std::vector<ModeTuple> out;
  for (const model::Mode& md : p.modes) out.emplace_back(md.omega, md.c, md.v, md.d);
  return out;
}

// A list of (omega, c, v, d), each a finite number: modes[i] names the bad one.
std::vector<model::Mode> ModesFrom(const py::object& modes) {
  std::vector<model::Mode> out;
  if (py::isinstance<py::str>(modes) || !py::hasattr(modes, "__iter__")) {
    throw py::type_error("modes must be a list of (omega, c, v, d) tuples, not " +
                         py::str(py::type::of(modes).attr("__name__")).cast<std::string>());
  }
  size_t i = 0;
  for (const py::handle& h : modes) {
    const std::string where = "modes[" + std::to_string(i++) + "]";
    if (py::isinstance<py::str>(h) || !py::hasattr(h, "__len__") || py::len(h) != 4) {
      throw InputError(where + ": expected a tuple (omega, c, v, d) [rad/s]");
    }
    const py::sequence t = py::reinterpret_borrow<py::sequence>(h);
    double x[4];
    for (size_t k = 0; k < 4; ++k) x[k] = Number(t[k], (where + "." + "wcvd"[k]).c_str());
    out.push_back({x[0], x[1], x[2], x[3]});
  }
  return out;
}

std::optional<double> CheckedPeriod(std::optional<double> T) {
  if (T && !(*T > 0.0 && std::isfinite(*T))) throw InputError("sample_period_s = " + G(*T) + ": must be finite and > 0");
  return T;
}

// The model JSON as the CLI writes it, checked by the CLI's reader
// (io::ParseModelJson: finite, the plausible range, the delay's and the
// period's bounds, the covariance), so that a Model never holds and save()
// never writes what `zwidth` refuses to read.
nlohmann::json CheckedJson(const io::ModelFile& mf) {
  mf.plant.Validate();  // its messages name the keyword (m, modes[0].omega, ...)
  nlohmann::json j = io::ModelToJson(mf);
  io::ParseModelJson(j.dump(), "the model");
  return j;
}

// The model after `change`, kept only when the reader takes it.
template <typename F>
void Change(io::ModelFile& mf, F&& change) {
  io::ModelFile m = mf;
  change(m);
  CheckedJson(m);
  mf = std::move(m);
}

std::string ReprOf(const io::ModelFile& mf) {
  std::string s = "<zwidth.Model m=" + G(mf.plant.m) + " b=" + G(mf.plant.b) + " modes=[";
  for (size_t i = 0; i < mf.plant.modes.size(); ++i) {
    const model::Mode& md = mf.plant.modes[i];
    s += (i ? ", (" : "(") + G(md.omega) + ", " + G(md.c) + ", " + G(md.v) + ", " + G(md.d) + ")";
  }
  s += "] delay_samples=" + std::to_string(mf.plant.delay_samples);
  if (mf.sample_period_s) s += " sample_period_s=" + G(*mf.sample_period_s);
  if (mf.fit.is_object() && mf.fit.contains("quality")) s += " fit=" + mf.fit["quality"].get<std::string>();
  return s + ">";
}

py::object StdOf(const io::ModelFile& mf) {
  if (!mf.std_errors) return py::none();
  py::dict d;
  d["m"] = mf.std_errors->m;
  d["b"] = mf.std_errors->b;
  d["modes"] = ModesOf(*mf.std_errors);
  return d;
}

py::array_t<std::complex<double>> Response(const io::ModelFile& mf, const DoubleArray& f_hz,
                                           std::optional<double> period_s) {
  mf.plant.Validate();
  py::array_t<std::complex<double>> out = ShapedLike<std::complex<double>>(f_hz);
  const double* f = f_hz.data();
  std::complex<double>* h = out.mutable_data();
  const py::ssize_t n = f_hz.size();
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  if (!period_s) {
    py::gil_scoped_release release;
    for (py::ssize_t k = 0; k < n; ++k) h[k] = model::ContinuousResponse(mf.plant, kTwoPi * f[k]);
    return out;
  }
  io::ModelFile used = mf;  // its delay counted in samples of T
  const double T = ResolvePeriod(period_s, &used);
  py::gil_scoped_release release;
  const model::DiscreteResponse resp(model::DiscretizeZoh(used.plant, T));
  for (py::ssize_t k = 0; k < n; ++k) h[k] = resp.AtTheta(kTwoPi * f[k] * T);
  return out;
}

py::tuple StateSpaceOf(const io::ModelFile& mf, std::optional<double> period_s) {
  mf.plant.Validate();
  io::ModelFile used = mf;  // its delay counted in samples of the period
  const double T = period_s ? ResolvePeriod(period_s, &used) : 0.0;  // before used.plant is read
  const model::StateSpace s = period_s ? model::WithDelayStates(model::DiscretizeZoh(used.plant, T))
                                : model::ContinuousStateSpace(mf.plant);
  Eigen::MatrixXd B = s.B, C = s.C, D = Eigen::MatrixXd::Constant(1, 1, s.D);
  return py::make_tuple(s.A, B, C, D);
}

// Model(...), load / from_json / table1, save / to_json / export.
void DefModelConstructionAndFiles(py::class_<io::ModelFile>& cls) {
  cls.def(py::init([](const py::object& m_, const py::object& b, const py::object& modes,
                       const py::object& delay_samples, const std::string& name,
                       std::optional<double> sample_period_s) {
             io::ModelFile mf;
             mf.plant.m = Number(m_, "m");
             mf.plant.b = Number(b, "b");
             mf.plant.modes = ModesFrom(modes);
             mf.plant.delay_samples = Integer(delay_samples, "delay_samples");
             mf.plant.name = name;
             mf.sample_period_s = CheckedPeriod(sample_period_s);
             CheckedJson(mf);
             return mf;
           }),
           py::arg("m"), py::arg("b"), py::arg("modes") = std::vector<ModeTuple>{}, py::arg("delay_samples") = 0,
           py::arg("name") = "", py::arg("sample_period_s") = py::none(), kCLocale)
      .def_static("load", [](const py::object& path) { ScopedCLocale c; return io::ReadModelJson(PathFrom(path, "path")); }, py::arg("path"),
                  "Reads a model JSON file (the CLI's format); InputError names the file and the key.", kCLocale)
      .def_static("from_json", [](const std::string& text) { return io::ParseModelJson(text, "<string>"); },
                  py::arg("text"), "Parses model JSON text.", kCLocale)
      .def_static("table1", &io::Table1Model, "Table I of the paper (PHANToM 1.0, phi axis), built into the library.", kCLocale)
      .def("save", [](const io::ModelFile& mf, const py::object& p) {
             const std::string path = PathFrom(p, "path");
             CheckedJson(mf);
             ScopedCLocale c;
             io::ForgetNotedInputs();  // each call is its own command: a model loaded earlier may be replaced
             io::SetInvocation("zwidth.Model.save(" + nlohmann::json(io::Utf8ForJson(path)).dump() + ")");  // provenance
             io::WriteModelJson(path, mf);
           },
           py::arg("path"), "Writes the model JSON (atomically; the CLI reads it back).", kCLocale)
      .def("to_json", [](const io::ModelFile& mf) { return io::ModelToJson(mf).dump(2); },
           "The model JSON as text.", kCLocale)
      .def("export", [](const io::ModelFile& mf, const py::object& p, const std::string& format,
                        std::optional<double> period_s) {
             const std::string path = PathFrom(p, "path");
             io::ExportFormat f;
             if (!io::FromString(format, &f)) {
               throw InputError("format '" + format + "' is not one of json, hdf5, matlab, python, statespace, mat, mat73");
             }
             CheckedJson(mf);
             ScopedCLocale c;
             io::ForgetNotedInputs();
             io::ModelFile used = mf;  // as `zwidth export --period`: the delay converted
             const double T = period_s ? ResolvePeriod(period_s, &used) : 0.0;
             io::SetInvocation("zwidth.Model.export(" + nlohmann::json(io::Utf8ForJson(path)).dump() + ", " +
                               nlohmann::json(format).dump() + ")");  // provenance
             io::ExportModel(used, f, T, path);
           },
           py::arg("path"), py::arg("format"), py::arg("period_s") = py::none(),
           "Exports like `zwidth export` (format json | hdf5 | matlab | python | statespace); "
           "period_s adds the discrete model.", kCLocale);
}

// Model: the parameters (read-write), std, covariance, fit_info.
void DefModelParameters(py::class_<io::ModelFile>& cls) {
  cls.def_property("m", [](const io::ModelFile& mf) { return mf.plant.m; },
                    [](io::ModelFile& mf, const py::object& v) { Change(mf, [&](io::ModelFile& c) { c.plant.m = Number(v, "m"); }); }, "rigid-body inertia [kg m^2]")
      .def_property("b", [](const io::ModelFile& mf) { return mf.plant.b; },
                    [](io::ModelFile& mf, const py::object& v) { Change(mf, [&](io::ModelFile& c) { c.plant.b = Number(v, "b"); }); }, "rigid-body viscous damping [N m s/rad]")
      .def_property("modes", [](const io::ModelFile& mf) { return ModesOf(mf.plant); },
                    [](io::ModelFile& mf, const py::object& t) {
                      Change(mf, [&](io::ModelFile& c) {
                        c.plant.modes = ModesFrom(t);
                        // The covariance and std are of the old sections: dropped, never kept truncated.
                        c.log_covariance.clear();
                        c.std_errors.reset();
                      });
                    },
                    "list of (omega, c, v, d) per section [rad/s]: pole pair w, its damping c = 2 zeta w, "
                    "zero pair v, its damping d. Setting it drops the covariance and std (they were of the "
                    "old sections).")
      .def_property("delay_samples", [](const io::ModelFile& mf) { return mf.plant.delay_samples; },
                    [](io::ModelFile& mf, const py::object& v) {
                      Change(mf, [&](io::ModelFile& c) { c.plant.delay_samples = Integer(v, "delay_samples"); });
                    },
                    "input delay of the sampled model [samples]")
      .def_property("name", [](const io::ModelFile& mf) { return mf.plant.name; },
                    [](io::ModelFile& mf, const std::string& v) { mf.plant.name = v; }, "free text")
      .def_property("units", [](const io::ModelFile& mf) { return std::string(model::Units(mf.linear).word); },
                    [](io::ModelFile& mf, const std::string& v) { mf.linear = io::ParseUnitsWord(v, "units"); },
                    "the axis: 'rotary' (kg m^2, N m s/rad, rad) or 'linear' (kg, N s/m, m); kept in the "
                    "model file, and every label that reads the model follows it")
      .def_property("sample_period_s", [](const io::ModelFile& mf) { return mf.sample_period_s; },
                    [](io::ModelFile& mf, std::optional<double> v) {
                      Change(mf, [&](io::ModelFile& c) { c.sample_period_s = CheckedPeriod(v); });
                    },
                    "sample period the model was fitted at [s], or None")
      .def_property_readonly("std", &StdOf,
                             "standard errors {'m', 'b', 'modes': [(omega, c, v, d), ...]} of a fitted model "
                             "(inf where unknown), else None")
      .def_property("covariance", &CovarianceOf,
                    [](io::ModelFile& mf, const py::object& c) {
                      if (c.is_none()) { mf.log_covariance.clear(); return; }
                      // An (n, n) array, as the JSON's rows (io::ParseModelJson reads them).
                      const py::array a = CheckedArray(c, "covariance", false, 2);
                      const auto n = static_cast<py::ssize_t>(stability::LogParameterNames(mf.plant).size());
                      if (a.ndim() != 2 || a.shape(0) != n || a.shape(1) != n) {
                        throw InputError("covariance has shape " + py::str(a.attr("shape")).cast<std::string>() +
                                         ": give the (" + std::to_string(n) + ", " + std::to_string(n) +
                                         ") matrix of covariance_names");
                      }
                      std::vector<double> v = Samples(a.attr("ravel")(), "covariance");
                      Change(mf, [&](io::ModelFile& m) { m.log_covariance = std::move(v); });
                    },
                    "the fit's parameter covariance in log space (the JSON's \"covariance\"), an (2 + 4 N)^2 "
                    "array ordered as covariance_names; None when the model has none. Gives 'std' in "
                    "ZWidth.summary().")
      .def_property_readonly("covariance_names",
                             [](const io::ModelFile& mf) { return stability::LogParameterNames(mf.plant); },
                             "the covariance's rows: log m, log b, then log omega, log c, log v, log d per section")
      .def_property_readonly("fit_info", [](const io::ModelFile& mf) { return JsonToPython(mf.fit); },
                             "the fit metrics stored with a fitted model (dict), else None")
      .def_property_readonly("num_states", [](const io::ModelFile& mf) { return mf.plant.num_states(); })
      // The friction as model.json stores it (issue 32; fit/friction_fit.h).
      .def_property_readonly("friction",
                             [](const io::ModelFile& mf) {
                               return mf.friction ? JsonToPython(io::ModelToJson(mf)["friction"]) : py::object(py::none());
                             },
                             "Coulomb friction and offset (dict of model.json's 'friction': coulomb_pos, coulomb_neg, "
                             "offset, breakaway_pos, breakaway_neg; input units), else None")
      .def_property_readonly("friction_std",
                             [](const io::ModelFile& mf) {
                               const nlohmann::json j = io::ModelToJson(mf);
                               return j.contains("std") && j["std"].contains("friction")
                                          ? JsonToPython(j["std"]["friction"]) : py::object(py::none());
                             },
                             "the friction's std (dict, None = unknown), else None")
      .def_property_readonly("encoder_step",
                             [](const io::ModelFile& mf) { return mf.encoder_step; },
                             "the position's step per encoder count (rad, or m on a linear axis) read from the log "
                             "the model was fitted on (model.json's 'encoder_step'), else None");
}

// Model: validate, response, state_space, repr, pickling.
void DefModelComputations(py::class_<io::ModelFile>& cls) {
  cls.def("validate", [](const io::ModelFile& mf) { mf.plant.Validate(); },
           "Raises InputError naming the first invalid parameter.", kCLocale)
      .def("response", &Response, py::arg("f_hz"), py::arg("period_s") = py::none(),
           R"doc(Frequency response at f_hz (array-like, Hz), complex, same shape.
period_s=None: G(j 2 pi f) of eq. (1). Else the exact zero-order-hold
sampled model G_d(e^{j 2 pi f T}) z^-delay_samples at T = period_s.)doc", kCLocale)
      .def("state_space", &StateSpaceOf, py::arg("period_s") = py::none(),
           R"doc((A, B, C, D) NumPy matrices. period_s=None: the continuous cascade
realisation of model/state_space.h. Else its exact ZOH discretisation with
the input delay realised as extra states.)doc", kCLocale)
      .def("__repr__", &ReprOf, kCLocale);
  DefValue(cls, [](const io::ModelFile& mf) { return py::make_tuple(io::ModelToJson(mf).dump()); },
           [](const py::tuple& t) { return io::ParseModelJson(t[0].cast<std::string>(), "<pickle>"); });
}

}  // namespace

void BindModel(py::module_& m) {
  py::class_<io::ModelFile> cls(m, "Model", R"doc(
The plant of eq. (1) of Gil et al.: rigid body 1/(m s^2 + b s) times N
resonance/antiresonance sections w^2 (s^2 + d s + v^2) / (v^2 (s^2 + c s + w^2)),
with an optional integer input delay of the sampled model. SI units, rad/s.

Model(m, b, modes=[], delay_samples=0, name="", sample_period_s=None)
  modes: a list of (omega, c, v, d) tuples [rad/s].
Model.load(path), model.save(path): the model JSON of the CLI.
Model.table1(): Table I of the paper (PHANToM 1.0, phi axis), built in.)doc");
  DefModelConstructionAndFiles(cls);
  DefModelParameters(cls);
  DefModelComputations(cls);
}

}  // namespace zwidth::python
