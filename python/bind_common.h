// Shared helpers of the Python bindings: NumPy <-> std::vector conversion,
// nlohmann::json -> Python objects, and the period rule of the CLI.
//
// Each area of the library has one Bind* function in its own file
// (bind_model.cc, bind_ident.cc, bind_fit.cc, bind_stability.cc), so that a
// new function of fit/ or stability/ is a few lines in one file.
#pragma once

#include <chrono>
#include <cmath>
#include <complex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "io/model_json.h"

namespace zwidth::python {

namespace py = pybind11;

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

// A row-major n x n covariance (log space) as an (n, n) array, None when empty.
inline py::object SquareArray(const std::vector<double>& v) {
  if (v.empty()) return py::none();
  const auto n = static_cast<py::ssize_t>(std::llround(std::sqrt(static_cast<double>(v.size()))));
  py::array_t<double> out({n, n});
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}
inline py::object CovarianceOf(const io::ModelFile& mf) { return SquareArray(mf.log_covariance); }

// The CLI's --period rule (apps::ResolvePeriod): the given period when not
// None (must be finite and > 0), else the model's sample_period_s, else 1 ms.
double ResolvePeriod(const std::optional<double>& period_s, const io::ModelFile& model);

void BindModel(py::module_& m);
void BindIdent(py::module_& m);
void BindFit(py::module_& m);
void BindStability(py::module_& m);

}  // namespace zwidth::python
