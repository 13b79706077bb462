// Shared helpers of the Python bindings: NumPy <-> std::vector conversion,
// nlohmann::json -> Python objects, and the period rule of the CLI.
//
// Each area of the library has one Bind* function in its own file
// (bind_model.cc, bind_ident.cc, bind_fit.cc, bind_stability.cc), so that a
// new function of fit/ or stability/ is a few lines in one file.
#pragma once

#include <charconv>
#include <chrono>
#include <clocale>
#include <cmath>
#include <complex>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <locale.h>

#include "io/model_json.h"
#include "model/c_locale.h"
#include "model/sample_period.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

namespace zwidth::python {

namespace py = pybind11;

// The C locale on the calling thread for the whole of a call (uselocale; other
// threads and Python's own locale-aware functions keep theirs): the messages
// the library formats with printf's %g or std::to_string (an InputError's
// "overlap = -1.000000") are the CLI's under a German locale too. One per
// binding, as the extra `kCLocale` of every def.
struct CLocaleGuard {
  CLocaleGuard() : old_(uselocale(CLocale())) {}
  ~CLocaleGuard() { uselocale(old_); }
  CLocaleGuard(const CLocaleGuard&) = delete;
  CLocaleGuard& operator=(const CLocaleGuard&) = delete;

 private:
  static locale_t CLocale() {
    static const locale_t c = newlocale(LC_ALL_MASK, "C", nullptr);  // kept for the process's life
    return c;
  }
  locale_t old_;
};
inline constexpr py::call_guard<CLocaleGuard> kCLocale{};

// zwidth.Log: a log in memory, torque input u, position output y, uniformly
// sampled (bind_ident.cc; zwidth.fit reads it again for the friction fit).
struct PyLog {
  std::string source;
  double sample_rate_hz = 0.0;
  std::vector<double> u, y;
  double period_s() const { return model::SamplePeriod(sample_rate_hz); }
};

// A C-contiguous double array view of any array-like (lists, scalars, ints).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

inline std::vector<double> ToVector(const DoubleArray& a) {
  return std::vector<double>(a.data(), a.data() + a.size());
}

inline py::array_t<double> ToArray(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

inline py::array_t<std::complex<double>> ToArray(const std::vector<std::complex<double>>& v) {
  py::array_t<std::complex<double>> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// An output array of the same shape as `like`.
template <typename T>
py::array_t<T> ShapedLike(const py::array& like) {
  std::vector<py::ssize_t> shape(like.shape(), like.shape() + like.ndim());
  return py::array_t<T>(shape);
}

// Seconds spent in the library by this thread's last timed call (fit, ZWidth.critical),
// measured inside the call around the library work alone, so that
// bench/python_overhead.py can pair it with the Python-side time of that call.
inline thread_local double g_last_cpp_seconds = 0.0;  // per thread: calls run without the GIL

// Times f() into g_last_cpp_seconds.
template <typename F>
void TimedCpp(F&& f) {
  const auto a = std::chrono::steady_clock::now();
  f();
  g_last_cpp_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

py::object JsonToPython(const nlohmann::json& j);

// v in %g (six significant digits) whatever the locale: how reprs show numbers
// (std::to_string's %f shows 1e-7 as 0.000000).
inline std::string G(double v) { return zwidth::FormatG(v); }

// The samples of an `ndim`-D array of numbers (ints or floats; complex with
// `complex`), every one finite: the argument `name`'s rule, with a message saying
// what to pass. A non-numeric dtype is a TypeError (as NumPy's own), a wrong
// shape or a NaN/inf sample an InputError (the flat index of the first).
py::array CheckedArray(const py::handle& a, const char* name, bool complex = false, int ndim = 1);
std::vector<double> Samples(const py::handle& a, const char* name);
std::vector<std::complex<double>> ComplexSamples(const py::handle& a, const char* name);
// A finite number (a float, int or NumPy scalar; not a bool or a string).
double Number(const py::handle& v, const char* name);
// An integer (int or NumPy integer; not a bool or a float) as Python's own
// `range(2.5)` refuses a float: TypeError.
int Integer(const py::handle& v, const char* name);

// A vector's bytes and back: the pickled state of the arrays (exact, NaN kept).
template <typename T>
py::bytes Bytes(const std::vector<T>& v) {
  return py::bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}
template <typename T>
std::vector<T> FromBytes(const py::handle& b) {
  const std::string s = b.cast<std::string>();
  std::vector<T> v(s.size() / sizeof(T));
  std::memcpy(v.data(), s.data(), v.size() * sizeof(T));
  return v;
}

// Two states equal: tuples and lists element by element, floats equal or both NaN.
bool SameState(const py::handle& a, const py::handle& b);

// Value semantics from one state: pickling (and so copy.copy, copy.deepcopy and
// multiprocessing) and ==, which compares the states (NaN equal to NaN).
template <class T, class Get, class Set, class... Options>
void DefValue(py::class_<T, Options...>& cls, Get get, Set set) {
  cls.def(py::pickle(get, set), kCLocale);
  cls.def("__eq__", [get](const T& a, const py::object& b) -> py::object {
    if (!py::isinstance<T>(b)) return py::reinterpret_borrow<py::object>(Py_NotImplemented);
    return py::bool_(SameState(get(a), get(b.template cast<const T&>())));
  });
  cls.attr("__hash__") = py::none();  // mutable or array-valued: unhashable, as NumPy arrays
}

// The C locale for this thread while it lives (model/c_locale.h): text the
// library writes or reads is the same under a German locale that Python's
// locale.setlocale chose.
using zwidth::ScopedCLocale;

// A row-major n x n covariance (log space) as an (n, n) array, None when empty.
inline py::object SquareArray(const std::vector<double>& v) {
  if (v.empty()) return py::none();
  const auto n = static_cast<py::ssize_t>(std::llround(std::sqrt(static_cast<double>(v.size()))));
  py::array_t<double> out({n, n});
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}
inline py::object CovarianceOf(const io::ModelFile& mf) { return SquareArray(mf.log_covariance); }

// The CLI's --period rule (io::ResolveModelPeriod): the given period when not
// None (in [1e-6, 0.1] s), else the model's sample_period_s, else 1 ms; the
// model's delay converted to it (a UserWarning says so, in Python's words).
// Under the GIL.
double ResolvePeriod(const std::optional<double>& period_s, io::ModelFile* model);

// A path or a sequence of paths (str or os.PathLike), as estimate_logs and
// run take them; TypeError for another item.
std::vector<std::string> PathsFrom(const py::object& paths);
// One path argument `name` (str, bytes or os.PathLike, encoded as os.fsencode
// does): TypeError for another type, InputError for a NUL byte, which the C
// library would take as the end of the name (another file).
std::string PathFrom(const py::handle& p, const char* name);
const std::string& CheckedPath(const std::string& path, const char* name);

// m.def(name, f, args..., extra...) with the keyword arguments given as a tuple.
template <class F, class Args, class... Extra>
void DefWith(py::module_& m, const char* name, F&& f, Args&& args, Extra&&... extra) {
  std::apply([&](auto&&... a) { m.def(name, std::forward<F>(f), a..., std::forward<Extra>(extra)...); },
             std::forward<Args>(args));
}

// The CLI's loop flags (flags/loop_flags.cc) as keywords: a first-order
// velocity low-pass at velocity_filter_hz (None: the raw difference) and the
// user's hand (M, B, K) (None: nobody holds the device).
stability::LoopOptions LoopFrom(std::optional<double> velocity_filter_hz,
                                std::optional<std::tuple<double, double, double>> hand, double T);

void BindModel(py::module_& m);
void BindIdent(py::module_& m);
void BindFit(py::module_& m);
void BindStability(py::module_& m);
void BindRun(py::module_& m);  // zwidth.run (bind_run.cc)

}  // namespace zwidth::python
