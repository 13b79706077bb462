// zwidth.ZWidth (stability/zwidth.h), zwidth.relay (stability/relay.h) and
// zwidth.check (the scene check of `zwidth check`).
#include <cmath>
#include <limits>
#include <optional>

#include "analysis/plant_stability.h"
#include "analysis/scene_check.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "python/bind_common.h"
#include "stability/loop_options.h"
#include "stability/passivity.h"
#include "stability/relay.h"
#include "stability/uncertainty.h"
#include "stability/velocity_filter.h"
#include "stability/zwidth.h"

namespace zwidth::python {
namespace {

using Hand = std::tuple<double, double, double>;

// A ZWidth with what it was built from (its pickled state).
struct PyZWidth {
  io::ModelFile model;
  std::optional<double> period_arg;  // as given (None: the model's, else 1 ms)
  int delay_samples = 0;
  stability::BoundaryOptions options;
  std::optional<double> velocity_filter_hz;
  std::optional<Hand> hand;
  stability::LoopOptions loop;
  std::unique_ptr<stability::ZWidth> z;
};

}  // namespace

stability::LoopOptions LoopFrom(std::optional<double> velocity_filter_hz,
                                std::optional<std::tuple<double, double, double>> hand, double T) {
  stability::LoopOptions l;
  if (velocity_filter_hz && !std::isfinite(*velocity_filter_hz)) {
    throw InputError("velocity_filter_hz = " + G(*velocity_filter_hz) + ": must be finite (None for no filter)");
  }
  if (velocity_filter_hz) stability::SetLowPassFilter(*velocity_filter_hz, T, &l);
  if (hand) l.hand = {std::get<0>(*hand), std::get<1>(*hand), std::get<2>(*hand)};
  std::string why;
  if (!l.IsValid(&why)) throw InputError(why);
  return l;
}

namespace {


// A loop delay by the CLI's rule of --delays (io::LoopDelaysProblem: [0, 1000] samples).
void CheckDelay(int d, const char* name) {
  if (const std::string why = io::LoopDelaysProblem({d}, name); !why.empty()) throw InputError(why);
}

// B (or K) values as a C-order double array, each finite and >= 0 as `zwidth
// check` requires of a scene's K and B: `name`[i] names the first bad one.
DoubleArray Gains(const py::object& v, const char* name) {
  py::module_ np = py::module_::import("numpy");
  py::array a = np.attr("asarray")(v);
  const char kind = a.dtype().kind();
  if (std::string("iuf").find(kind) == std::string::npos) {
    throw py::type_error(std::string(name) + " must be a number or an array of real numbers, not of dtype " +
                         py::str(a.dtype()).cast<std::string>());
  }
  const DoubleArray d = DoubleArray::ensure(a);
  for (py::ssize_t i = 0; i < d.size(); ++i) {
    const double x = d.data()[i];
    if (!(std::isfinite(x) && x >= 0.0)) {
      throw InputError(std::string(name) + (d.ndim() ? "[" + std::to_string(i) + "]" : "") + " = " + G(x) +
                       ": must be finite and >= 0");
    }
  }
  return d;
}
double Gain(double v, const char* name) { return Gains(py::float_(v), name).data()[0]; }

void Build(PyZWidth* p) {
  const double T = ResolvePeriod(p->period_arg, &p->model);  // p->model: its delay in samples of T
  p->loop = LoopFrom(p->velocity_filter_hz, p->hand, T);
  py::gil_scoped_release release;
  p->z = std::make_unique<stability::ZWidth>(p->model.plant, T, p->delay_samples, p->loop, p->options);
}

py::tuple ZWidthState(const PyZWidth& z) {
  const stability::BoundaryOptions& o = z.options;
  return py::make_tuple(io::ModelToJson(z.model).dump(), z.period_arg, z.delay_samples,
                        py::make_tuple(o.min_grid_points, o.grid_points_per_delay, o.theta_tolerance, o.verify),
                        z.velocity_filter_hz, z.hand);
}

// A ZWidth from what the constructor takes, each value checked (the
// constructor's and the pickled state's one way in).
std::unique_ptr<PyZWidth> NewZWidth(const io::ModelFile& model, std::optional<double> period_s,
                                    const py::object& delay_samples, const stability::BoundaryOptions& options,
                                    std::optional<double> velocity_filter_hz, std::optional<Hand> hand) {
  auto p = std::make_unique<PyZWidth>();
  p->delay_samples = Integer(delay_samples, "delay_samples");
  CheckDelay(p->delay_samples, "delay_samples");
  p->options = options;
  std::string why;
  if (!p->options.IsValid(&why)) throw InputError(why);
  model.plant.Validate();
  p->model = model;
  p->period_arg = period_s;
  p->velocity_filter_hz = velocity_filter_hz;
  p->hand = hand;
  Build(p.get());
  return p;
}

std::unique_ptr<PyZWidth> ZWidthFrom(const py::tuple& t) {
  const py::tuple o = t[3];
  stability::BoundaryOptions options;
  options.min_grid_points = o[0].cast<int>();
  options.grid_points_per_delay = o[1].cast<int>();
  options.theta_tolerance = o[2].cast<double>();
  options.verify = o[3].cast<bool>();
  return NewZWidth(io::ParseModelJson(t[0].cast<std::string>(), "<pickle>"), t[1].cast<std::optional<double>>(),
                   t[2], options, t[4].cast<std::optional<double>>(), t[5].cast<std::optional<Hand>>());
}

std::string ZWidthRepr(const PyZWidth& z) {
  std::string s = "<zwidth.ZWidth delay_samples=" + std::to_string(z.delay_samples) +
                  " (total " + std::to_string(z.z->total_delay()) + ") period_s=" + G(z.z->period_s()) +
                  " model m=" + G(z.model.plant.m) + " b=" + G(z.model.plant.b) +
                  " modes=" + std::to_string(z.model.plant.modes.size());
  if (z.model.fit.is_object() && z.model.fit.contains("quality")) {
    s += " fit=" + z.model.fit["quality"].get<std::string>();
    if (z.model.fit["quality"] == "poor") s += " (do not trust this Z-width: see the fit's quality_reasons)";
  }
  if (z.velocity_filter_hz) s += " velocity_filter_hz=" + G(*z.velocity_filter_hz);
  if (z.hand) s += " hand=(" + G(std::get<0>(*z.hand)) + ", " + G(std::get<1>(*z.hand)) + ", " + G(std::get<2>(*z.hand)) + ")";
  return s + ">";
}

// Applies f to every B (GIL released); returns arrays shaped like B, or
// Python scalars when B is a scalar.
template <typename F>
void ForEachB(const DoubleArray& B, F&& f) {
  const double* b = B.data();
  const py::ssize_t n = B.size();
  py::gil_scoped_release release;
  for (py::ssize_t k = 0; k < n; ++k) f(k, b[k]);
}

bool IsScalar(const py::object& o) { return py::array::ensure(o).ndim() == 0; }


// A scene path, or a list of {"name", "K", "B"} dicts or (name, K, B) tuples
// checked by the reader's rules (io::ParseScene of the same objects as JSON):
// a list is refused exactly where the same objects in a file are.
std::vector<io::SceneObject> SceneFrom(const py::object& scene) {
  if (py::isinstance<py::str>(scene) || py::isinstance<py::bytes>(scene) || py::hasattr(scene, "__fspath__")) {
    return io::ReadScene(PathFrom(scene, "scene"));
  }
  if (!py::hasattr(scene, "__iter__")) {
    throw py::type_error("scene must be a scene file's path or a list of objects, not " +
                         py::str(py::type::of(scene).attr("__name__")).cast<std::string>());
  }
  nlohmann::json objects = nlohmann::json::array();
  const py::module_ np = py::module_::import("numpy");
  // A Python value as the JSON the reader would see: numbers (not bools) as
  // numbers (NaN and inf named here: JSON has none), anything else as its text.
  auto value = [&](const py::handle& v, const std::string& where, const char* key) -> nlohmann::json {
    if (v.is_none()) return nullptr;
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    const bool number = !py::isinstance<py::bool_>(v) && !py::isinstance(v, np.attr("bool_")) &&
                        py::hasattr(v, "__float__");
    if (!number) return py::repr(v).cast<std::string>();
    const double x = v.cast<double>();
    if (!std::isfinite(x)) throw InputError("scene: " + where + ": '" + key + "' = " + G(x) + " must be finite and >= 0");
    return x;
  };
  size_t i = 0;
  for (const py::handle& h : scene) {
    const std::string where = "objects[" + std::to_string(i++) + "]";
    nlohmann::json o = nlohmann::json::object();
    if (py::isinstance<py::dict>(h)) {
      for (const auto& kv : py::reinterpret_borrow<py::dict>(h)) {
        const std::string k = py::str(kv.first).cast<std::string>();
        o[k] = value(kv.second, where, k.c_str());
      }
    } else {
      if (py::isinstance<py::str>(h) || !py::hasattr(h, "__len__") || py::len(h) != 3) {
        throw InputError("scene: " + where + ": expected {'name', 'K', 'B'} or (name, K, B)");
      }
      const py::sequence t = py::reinterpret_borrow<py::sequence>(h);
      if (!t[0].is_none()) o["name"] = value(t[0], where, "name");
      o["K"] = value(t[1], where, "K");
      o["B"] = value(t[2], where, "B");
    }
    objects.push_back(std::move(o));
    if (objects.size() > io::kMaxSceneObjects) break;  // the reader names the bound
  }
  return io::ParseScene(nlohmann::json{{"objects", objects}}.dump(), "scene");
}

// zwidth.CriticalPoint: the boundary at one B.
void BindCriticalPoint(py::module_& m) {
  py::class_<stability::CriticalPoint> cls(m, "CriticalPoint", "The Z-width boundary at one B (stability/zwidth.h).");
  DefValue(cls,
           [](const stability::CriticalPoint& c) {
             return py::make_tuple(c.B, c.K_cr, c.f_cr_hz, c.unstable_at_zero_k, c.verified, c.K_margin, c.f_margin_hz);
           },
           [](const py::tuple& t) {
             stability::CriticalPoint c;
             c.B = t[0].cast<double>();
             c.K_cr = t[1].cast<double>();
             c.f_cr_hz = t[2].cast<double>();
             c.unstable_at_zero_k = t[3].cast<bool>();
             c.verified = t[4].cast<bool>();
             c.K_margin = t[5].cast<double>();
             c.f_margin_hz = t[6].cast<double>();
             return c;
           });
  cls.def_readonly("B", &stability::CriticalPoint::B, "virtual damping [N m s/rad]")
      .def_readonly("K_cr", &stability::CriticalPoint::K_cr,
                    "smallest K > 0 with a closed-loop pole on the unit circle [N m/rad]; 0 when unstable as K -> 0+, "
                    "inf when no crossing exists")
      .def_readonly("f_cr_hz", &stability::CriticalPoint::f_cr_hz, "ultimate frequency [Hz]")
      .def_readonly("unstable_at_zero_k", &stability::CriticalPoint::unstable_at_zero_k)
      .def_readonly("verified", &stability::CriticalPoint::verified,
                    "Schur-Cohn: stable at 0.999999 K_cr, unstable at 1.000001 K_cr")
      .def_readonly("K_margin", &stability::CriticalPoint::K_margin,
                    "the paper's eq. (4) reading (MATLAB margin()); not the Z-width past B_max")
      .def_readonly("f_margin_hz", &stability::CriticalPoint::f_margin_hz)
      .def_property_readonly("margin_agrees", [](const stability::CriticalPoint& c) { return c.AgreesWithMargin(); })
      .def("__iter__", [](const stability::CriticalPoint& c) {
        return py::iter(py::make_tuple(c.K_cr, c.f_cr_hz));
      }, "K_cr, f_cr_hz = point", kCLocale)
      .def("__repr__", [](const stability::CriticalPoint& c) {
        return "<zwidth.CriticalPoint B=" + G(c.B) + " K_cr=" + G(c.K_cr) + " f_cr_hz=" + G(c.f_cr_hz) +
               (c.verified ? " verified" : " not verified") + (c.unstable_at_zero_k ? " unstable_at_zero_k" : "") +
               (c.AgreesWithMargin() ? "" : " (margin() reads K=" + G(c.K_margin) + ")") + ">";
      }, kCLocale);
}

// ZWidth(...) and its read-only properties.
void DefZWidthConstruction(py::class_<PyZWidth>& cls) {
  cls.def(py::init([](const io::ModelFile& model, std::optional<double> period_s, const py::object& delay_samples,
                       int min_grid_points, int grid_points_per_delay, double theta_tolerance, bool verify,
                       std::optional<double> velocity_filter_hz, std::optional<Hand> hand) {
             stability::BoundaryOptions options;
             options.min_grid_points = min_grid_points;
             options.grid_points_per_delay = grid_points_per_delay;
             options.theta_tolerance = theta_tolerance;
             options.verify = verify;
             return NewZWidth(model, period_s, delay_samples, options, velocity_filter_hz, hand);
           }),
           py::arg("model"), py::arg("period_s") = py::none(), py::arg("delay_samples") = 2,
           py::arg("min_grid_points") = stability::BoundaryOptions{}.min_grid_points,
           py::arg("grid_points_per_delay") = stability::BoundaryOptions{}.grid_points_per_delay,
           py::arg("theta_tolerance") = stability::BoundaryOptions{}.theta_tolerance,
           py::arg("verify") = stability::BoundaryOptions{}.verify, py::arg("velocity_filter_hz") = py::none(),
           py::arg("hand") = py::none(), kCLocale)
      .def("__repr__", &ZWidthRepr, kCLocale)
      .def_property_readonly("period_s", [](const PyZWidth& z) { return z.z->period_s(); }, "loop sample period T [s]")
      .def_property_readonly("delay_samples", [](const PyZWidth& z) { return z.delay_samples; }, "loop delay d")
      .def_property_readonly("total_delay_samples", [](const PyZWidth& z) { return z.z->total_delay(); },
                             "d plus the model's own delay")
      .def_readonly("model", &PyZWidth::model)
      .def_property_readonly("filter_b", [](const PyZWidth& z) { return z.loop.filter_b; },
                             "velocity filter numerator (powers of z^-1); [] without a filter")
      .def_property_readonly("filter_a", [](const PyZWidth& z) { return z.loop.filter_a; })
      .def_property_readonly("hand", [](const PyZWidth& z) -> py::object {
             if (z.loop.hand.IsNone()) return py::none();
             return py::make_tuple(z.loop.hand.M, z.loop.hand.B, z.loop.hand.K);
           }, "(M, B, K) of the user's hand, None when nobody holds the device");
}

// ZWidth: stable intervals and the critical point at one B.
void DefZWidthAtB(py::class_<PyZWidth>& cls) {
  cls.def("stable_intervals",
           [](const PyZWidth& z, double B) {
             Gain(B, "B");
             std::vector<stability::KInterval> iv;
             {
               py::gil_scoped_release release;
               iv = z.z->StableIntervals(B);
             }
             std::vector<std::pair<double, double>> out;
             for (const auto& k : iv) out.emplace_back(k.K_lo, k.K_hi);
             return out;
           },
           py::arg("B"),
           R"doc(Every stable K interval at damping B [N m s/rad], ascending: a list of
(K_lo, K_hi) tuples [N m/rad] (K_lo 0 means from K = 0+, K_hi may be inf). The
loop is stable at (K, B) exactly when K lies strictly inside one of them
(is_stable agrees); [] when no K > 0 is stable. Past B_max_from_zero the
first interval no longer starts at 0 (reopened bands).)doc", kCLocale)
      .def("critical",
           [](const PyZWidth& z, const py::object& B) -> py::object {
             const DoubleArray b = Gains(B, "B");
             py::array_t<double> K = ShapedLike<double>(b), f = ShapedLike<double>(b);
             double* k = K.mutable_data();
             double* fh = f.mutable_data();
             TimedCpp([&] {
               ForEachB(b, [&](py::ssize_t i, double v) {
                 const stability::CriticalPoint c = z.z->At(v);
                 k[i] = c.K_cr;
                 fh[i] = c.f_cr_hz;
               });
             });
             if (IsScalar(B)) return py::make_tuple(k[0], fh[0]);
             return py::make_tuple(K, f);
           },
           py::arg("B"),
           R"doc((K_cr, f_cr_hz) at B [N m s/rad]: floats for a scalar B, arrays shaped
like B for an array (the GIL is released over the sweep). K_cr is 0 where
the loop is unstable as K -> 0+ (B past B_max), inf with no crossing.)doc", kCLocale)
      .def("point", [](const PyZWidth& z, double B) {
             Gain(B, "B");
             py::gil_scoped_release release;
             return z.z->At(B);
           },
           py::arg("B"), "The full CriticalPoint at one B (with the margin() reading and the verification).", kCLocale);
}

// ZWidth: the boundary over an array of B, the crossings at one B.
void DefZWidthOverB(py::class_<PyZWidth>& cls) {
  cls.def("boundary",
           [](const PyZWidth& z, const py::object& B_in) {
             const DoubleArray B = Gains(B_in, "B");
             const py::ssize_t n = B.size();
             std::vector<stability::CriticalPoint> pts(static_cast<size_t>(n));
             ForEachB(B, [&](py::ssize_t i, double v) { pts[i] = z.z->At(v); });
             py::dict d;
             auto col = [&](const char* name, auto get) {
               using T = decltype(get(pts[0]));
               py::array_t<T> a = ShapedLike<T>(B);
               T* p = a.mutable_data();
               for (py::ssize_t i = 0; i < n; ++i) p[i] = get(pts[i]);
               d[name] = a;
             };
             if (n == 0) {
               for (const char* name : {"B", "K_cr", "f_cr_hz", "K_margin", "f_margin_hz"}) d[name] = ShapedLike<double>(B);
               for (const char* name : {"unstable_at_zero_k", "margin_agrees", "verified"}) d[name] = ShapedLike<bool>(B);
               return d;
             }
             col("B", [](const stability::CriticalPoint& c) { return c.B; });
             col("K_cr", [](const stability::CriticalPoint& c) { return c.K_cr; });
             col("f_cr_hz", [](const stability::CriticalPoint& c) { return c.f_cr_hz; });
             col("K_margin", [](const stability::CriticalPoint& c) { return c.K_margin; });
             col("f_margin_hz", [](const stability::CriticalPoint& c) { return c.f_margin_hz; });
             col("unstable_at_zero_k", [](const stability::CriticalPoint& c) { return c.unstable_at_zero_k; });
             col("margin_agrees", [](const stability::CriticalPoint& c) { return c.AgreesWithMargin(); });
             col("verified", [](const stability::CriticalPoint& c) { return c.verified; });
             return d;
           },
           py::arg("B"),
           "The columns of `zwidth boundary`'s CSV for one delay over an array of B: a dict of arrays "
           "B, K_cr, f_cr_hz, K_margin, f_margin_hz, unstable_at_zero_k, margin_agrees, verified.", kCLocale)
      .def("crossings",
           [](const PyZWidth& z, double B) {
             Gain(B, "B");
             std::vector<std::pair<double, double>> out;
             for (const auto& c : z.z->Crossings(B)) out.emplace_back(c.theta, c.K);
             return out;
           },
           py::arg("B"), "Every (theta [rad/sample], K) at which a closed-loop pole is on the unit circle.", kCLocale);
}

// ZWidth: stability at (K, B), the summary, the characteristic polynomial.
void DefZWidthSummary(py::class_<PyZWidth>& cls) {
  cls.def("is_stable",
           [](const PyZWidth& z, const py::object& K, const py::object& B) -> py::object {
             const DoubleArray k0 = Gains(K, "K"), b0 = Gains(B, "B");
             py::list both;
             try {
               both = py::module_::import("numpy").attr("broadcast_arrays")(k0, b0);
             } catch (py::error_already_set&) {  // NumPy's message names neither
               throw InputError("K has shape " + py::str(k0.attr("shape")).cast<std::string>() + " and B " +
                                py::str(b0.attr("shape")).cast<std::string>() + ": they must broadcast (NumPy's rules)");
             }
             const DoubleArray k = DoubleArray::ensure(both[0]);  // forcecast copies to C order
             const DoubleArray b = DoubleArray::ensure(both[1]);
             py::array_t<bool> out = ShapedLike<bool>(k);
             bool* o = out.mutable_data();
             const double* kp = k.data();
             ForEachB(b, [&](py::ssize_t i, double v) { o[i] = z.z->IsStable(kp[i], v); });
             if (out.ndim() == 0) return py::bool_(o[0]);
             return out;
           },
           py::arg("K"), py::arg("B"),
           "The closed loop's stability at (K [N m/rad], B [N m s/rad]) by the one test behind every answer "
           "(stable_intervals, summary, check): Schur-Cohn where the polynomial is well conditioned, else the "
           "closed-loop matrix's eigenvalues (stability_test in summary()); broadcasts arrays (K = 0 is "
           "taken as 0+). K and B must be finite and >= 0 (InputError naming the first that is not).", kCLocale)
      .def("summary",
           [](const PyZWidth& z, const py::object& monte_carlo, uint64_t seed) {
             // One entry of the CLI's summary JSON "delays" list (analysis::DelaySummaryJson, boundary --summary).
             const int mc = Integer(monte_carlo, "monte_carlo");
             if (mc < 0) throw InputError("monte_carlo = " + std::to_string(mc) + ": must be >= 0");
             if (mc > 0 && z.model.log_covariance.empty()) {
               throw InputError("monte_carlo needs a model with a covariance (a model fitted by zwidth.fit)");
             }
             nlohmann::json e;
             {
               py::gil_scoped_release release;
               const stability::DelaySummary s = z.z->Summarize();
               const bool has_cov = !z.model.log_covariance.empty();
               stability::SummaryStd sd;
               if (has_cov) {
                 sd = stability::SummaryStdDelta(z.model.plant, z.model.log_covariance, z.z->period_s(),
                                                 z.delay_samples, s, {}, z.loop);
               }
               const stability::Passivity pa(z.model.plant.b, z.z->period_s(), z.z->total_delay(), z.loop);
               std::optional<stability::MonteCarloResult> mcr;
               if (mc > 0) {
                 mcr = stability::SummaryMonteCarlo(z.model.plant, z.model.log_covariance, z.z->period_s(),
                                                    z.delay_samples, mc, seed, z.loop);
               }
               e = analysis::DelaySummaryJson(s, has_cov ? &sd : nullptr, z.delay_samples, z.model.plant, pa,
                                              mcr ? &*mcr : nullptr, seed);
             }
             return JsonToPython(e);
           },
           py::arg("monte_carlo") = 0, py::arg("seed") = 1,
           R"doc(K_cr(0), B_t, K_cr^max, B_max (the largest B with some stable K > 0),
B_max_from_zero (the paper's B_max), reopened_bands, passivity (K_P(0),
B_P_max) and, when the model carries a covariance, "std" (delta method): the
CLI's summary JSON, one entry of 'delays' (None for NaN/inf). monte_carlo=N
> 0 (--monte-carlo N --seed S) adds "monte_carlo" {samples, seed, std, mean}
from N seeded draws of the covariance (seconds per hundred draws; Ctrl-C
stops it with KeyboardInterrupt).)doc", kCLocale)
      .def("characteristic_polynomial",
           [](const PyZWidth& z, double K, double B) {
             return ToArray(z.z->CharacteristicPolynomial(Gain(K, "K"), Gain(B, "B")));
           },
           py::arg("K"), py::arg("B"),
           "Closed-loop characteristic polynomial coefficients, z^0 first. With many lightly damped, crowded\n"
           "modes its roots are ill-conditioned (numpy.roots can put a stable root outside the circle);\n"
           "is_stable decides by the closed loop's eigenvalues there (docs/zwidth.md).", kCLocale);
}

// zwidth.ZWidth: the Z-width of one loop.
void BindZWidth(py::module_& m) {
  py::class_<PyZWidth> cls(m, "ZWidth", R"doc(
The Z-width of the sampled loop of eq. (2),
  1 + z^-d (K + B (1 - z^-1)/T) G_d(z) = 0,
with G_d the exact ZOH plant (the model's own delay adds to d).

ZWidth(model, period_s=None, delay_samples=2, min_grid_points=2048,
       grid_points_per_delay=64, theta_tolerance=1e-13, verify=True,
       velocity_filter_hz=None, hand=None)
period_s=None: the model's sample_period_s, else 1 ms (as the CLI).
velocity_filter_hz: a first-order low-pass on the velocity of the B term,
cut-off in (0, Nyquist) Hz (--velocity-filter-hz); None: the raw difference.
hand: the user's hand (M, B, K) at the measured coordinate, each >= 0
(--hand M,B,K); None: nobody holds the device.)doc");
  DefValue(cls, &ZWidthState, &ZWidthFrom);
  DefZWidthConstruction(cls);
  DefZWidthAtB(cls);
  DefZWidthOverB(cls);
  DefZWidthSummary(cls);
}

// zwidth.RelayResult and zwidth.relay: the simulated relay experiment.
py::tuple RelayState(const stability::RelayResult& r) {
  return py::make_tuple(r.K_cr, r.f_cr_hz, static_cast<int>(r.status), r.relay_runs, r.unsettled, r.uncertainty,
                        r.band_low_hz, r.K_cr_peak, r.f_cr_peak_hz, Bytes(r.relay_force), Bytes(r.damping_force),
                        Bytes(r.command), Bytes(r.position));
}

stability::RelayResult RelayFrom(const py::tuple& t) {
  stability::RelayResult r;
  r.K_cr = t[0].cast<double>();
  r.f_cr_hz = t[1].cast<double>();
  r.status = static_cast<stability::RelayStatus>(t[2].cast<int>());
  r.relay_runs = t[3].cast<int>();
  r.unsettled = t[4].cast<double>();
  r.uncertainty = t[5].cast<double>();
  r.band_low_hz = t[6].cast<double>();
  r.K_cr_peak = t[7].cast<double>();
  r.f_cr_peak_hz = t[8].cast<double>();
  r.relay_force = FromBytes<double>(t[9]);
  r.damping_force = FromBytes<double>(t[10]);
  r.command = FromBytes<double>(t[11]);
  r.position = FromBytes<double>(t[12]);
  return r;
}

std::string RelayRepr(const stability::RelayResult& r) {
  std::string s = "<zwidth.RelayResult " + stability::ToString(r.status) + ": K_cr=" + G(r.K_cr) +
                  " f_cr_hz=" + G(r.f_cr_hz) + " (peak reading K=" + G(r.K_cr_peak) + " at " + G(r.f_cr_peak_hz) +
                  " Hz), " + std::to_string(r.relay_runs) + " runs";
  if (std::isfinite(r.uncertainty)) s += ", uncertainty " + G(r.uncertainty);
  if (r.unsettled > 1e-3) s += ", unsettled " + G(r.unsettled) + " (a longer seconds= settles it)";
  return s + ">";
}

void BindRelay(py::module_& m) {
  py::class_<stability::RelayResult> cls(m, "RelayResult", "The simulated relay experiment (stability/relay.h).");
  DefValue(cls, &RelayState, &RelayFrom);
  cls.def("__repr__", &RelayRepr, kCLocale)
      .def_readonly("K_cr", &stability::RelayResult::K_cr, "estimate [N m/rad]")
      .def_readonly("f_cr_hz", &stability::RelayResult::f_cr_hz)
      .def_property_readonly("status", [](const stability::RelayResult& r) { return stability::ToString(r.status); },
                             "refined | peak_reading | below_band | diverged | no_oscillation (stability/relay.h)")
      .def_property_readonly("refined", &stability::RelayResult::refined)
      .def_readonly("relay_runs", &stability::RelayResult::relay_runs)
      .def_readonly("unsettled", &stability::RelayResult::unsettled)
      .def_readonly("uncertainty", &stability::RelayResult::uncertainty)
      .def_property_readonly("below_band",
                             [](const stability::RelayResult& r) { return r.status == stability::RelayStatus::kBelowBand; })
      .def_readonly("band_low_hz", &stability::RelayResult::band_low_hz)
      .def_readonly("K_cr_peak", &stability::RelayResult::K_cr_peak, "the paper's reading (spectral peak)")
      .def_readonly("f_cr_peak_hz", &stability::RelayResult::f_cr_peak_hz)
      .def_property_readonly("oscillating", &stability::RelayResult::oscillating)
      .def_property_readonly("diverged",
                             [](const stability::RelayResult& r) { return r.status == stability::RelayStatus::kDiverged; })
      .def_property_readonly("relay_force", [](const stability::RelayResult& r) { return ToArray(r.relay_force); })
      .def_property_readonly("damping_force", [](const stability::RelayResult& r) { return ToArray(r.damping_force); })
      .def_property_readonly("command", [](const stability::RelayResult& r) { return ToArray(r.command); })
      .def_property_readonly("position", [](const stability::RelayResult& r) { return ToArray(r.position); });

  m.def("relay",
        [](const io::ModelFile& model, int delay_samples, double damping, std::optional<double> period_s,
           double amplitude, double seconds, double settle_fraction, std::optional<double> velocity_filter_hz,
           std::optional<std::tuple<double, double, double>> hand) {
          CheckDelay(delay_samples, "delay_samples");
          stability::RelayOptions o;
          io::ModelFile used = model;  // its delay counted in samples of o.period_s
          o.period_s = ResolvePeriod(period_s, &used);
          o.delay_samples = delay_samples;
          o.damping = damping;
          o.amplitude = amplitude;
          o.seconds = seconds;
          o.settle_fraction = settle_fraction;
          o.loop = LoopFrom(velocity_filter_hz, hand, o.period_s);
          stability::RelayResult r;
          {
            py::gil_scoped_release release;
            r = stability::SimulateRelay(used.plant, o);
          }
          if (r.status == stability::RelayStatus::kNoOscillation) throw ComputationError("the relay loop did not oscillate");
          return r;
        },
        py::arg("model"), py::arg("delay_samples"), py::arg("damping"), py::arg("period_s") = py::none(),
        py::arg("amplitude") = stability::RelayOptions{}.amplitude,
        py::arg("seconds") = stability::RelayOptions{}.seconds,
        py::arg("settle_fraction") = stability::RelayOptions{}.settle_fraction,
        py::arg("velocity_filter_hz") = py::none(), py::arg("hand") = py::none(),
        R"doc(The relay experiment of section IV, simulated as `zwidth relay` does it;
velocity_filter_hz and hand (M, B, K) as for ZWidth (the haptic loop).
Raises ComputationError when the loop neither oscillates nor diverges.)doc", kCLocale);
}

// zwidth.check: is each object of a scene stable?
void BindCheck(py::module_& m) {
  m.def("check",
        [](const py::object& scene, const io::ModelFile& model, int delay_samples, std::optional<double> period_s,
           std::optional<double> velocity_filter_hz, std::optional<std::tuple<double, double, double>> hand,
           double marginal_sigmas) {
          CheckDelay(delay_samples, "delay_samples");
          io::ModelFile used = model;  // its delay counted in samples of T
          const double T = ResolvePeriod(period_s, &used);
          const stability::LoopOptions loop = LoopFrom(velocity_filter_hz, hand, T);
          const std::vector<io::SceneObject> objs = SceneFrom(scene);
          analysis::SceneCheckOptions o;
          o.marginal_sigmas = marginal_sigmas;
          nlohmann::json out;
          {
            py::gil_scoped_release release;
            const analysis::SceneCheck sc = analysis::CheckScene(used.plant, used.log_covariance, T, delay_samples,
                                                                 {loop}, objs, o);
            out = analysis::SceneCheckJson(sc, objs, delay_samples, T, o);
            io::AddDelays(&out, delay_samples, used.plant.delay_samples);  // as `zwidth check --json`
          }
          return JsonToPython(out);
        },
        py::arg("scene"), py::arg("model"), py::arg("delay_samples"), py::arg("period_s") = py::none(),
        py::arg("velocity_filter_hz") = py::none(), py::arg("hand") = py::none(), py::arg("marginal_sigmas") = 2.0,
        R"doc(Is each object {name, K, B} of a haptic scene stable on this device?
scene: a scene JSON path ({"objects": [...]}) or a list of dicts / (name, K, B)
tuples; velocity_filter_hz and hand as for ZWidth. Returns the dict `zwidth
check --json` prints (each object with its stable intervals, its status
stable/marginal/unstable and, when the model has a covariance, its distance to
the nearest boundary in std, marginal within marginal_sigmas); the CLI exits
with status 3 when an object is unstable (4 when none is but some is marginal),
this returns normally.)doc", kCLocale);
}

}  // namespace

void BindStability(py::module_& m) {
  BindCriticalPoint(m);
  BindZWidth(m);
  BindRelay(m);
  BindCheck(m);
}

}  // namespace zwidth::python
