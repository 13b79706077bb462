// The argument checks shared by the bindings (bind_common.h).
#include <cmath>
#include <string>

#include "model/error.h"
#include "python/bind_common.h"

namespace zwidth::python {

py::array CheckedArray(const py::handle& a, const char* name, bool complex, int ndim) {
  py::module_ np = py::module_::import("numpy");
  py::array arr;
  try {
    arr = np.attr("asarray")(a);
  } catch (py::error_already_set& e) {  // ragged lists
    throw InputError(std::string(name) + ": cannot be read as a 1-D array of numbers (" + e.what() + ")");
  }
  const char kind = arr.dtype().kind();
  const std::string allowed = complex ? "iufc" : "iuf";
  if (allowed.find(kind) == std::string::npos) {
    throw py::type_error(std::string(name) + " must be an array of " + (complex ? "numbers" : "real numbers") +
                         " (float or int), not of dtype " + py::str(arr.dtype()).cast<std::string>());
  }
  if (arr.ndim() != ndim) {
    std::string shape = py::str(arr.attr("shape")).cast<std::string>();
    throw InputError(std::string(name) + " has shape " + shape +
                     (ndim == 1 ? ": pass a 1-D array (one signal; a column of a 2-D array is a[:, j])"
                                : ": pass a " + std::to_string(ndim) + "-D array"));
  }
  py::array finite = np.attr("isfinite")(arr);
  if (!finite.attr("all")().cast<bool>()) {
    const py::ssize_t i = np.attr("argmin")(finite).cast<py::ssize_t>();
    throw InputError(std::string(name) + "[" + std::to_string(i) + "] = " +
                     py::str(arr.attr("ravel")()[py::int_(i)]).cast<std::string>() +
                     ": every value must be finite (remove or interpolate the gaps first)");
  }
  return arr;
}

std::vector<double> Samples(const py::handle& a, const char* name) {
  const DoubleArray d = DoubleArray::ensure(CheckedArray(a, name));
  return ToVector(d);
}

std::vector<std::complex<double>> ComplexSamples(const py::handle& a, const char* name) {
  using ComplexArray = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>;
  const ComplexArray c = ComplexArray::ensure(CheckedArray(a, name, true));
  return std::vector<std::complex<double>>(c.data(), c.data() + c.size());
}

namespace {
bool IsNumpyBool(const py::handle& v) {
  return py::isinstance(v, py::module_::import("numpy").attr("bool_"));
}
std::string TypeName(const py::handle& v) {
  return py::str(py::type::of(v).attr("__name__")).cast<std::string>();
}
}  // namespace

double Number(const py::handle& v, const char* name) {
  if (py::isinstance<py::bool_>(v) || IsNumpyBool(v) || py::isinstance<py::str>(v) || !py::hasattr(v, "__float__")) {
    throw py::type_error(std::string(name) + " must be a number, not " + TypeName(v));
  }
  const double x = v.cast<double>();
  if (!std::isfinite(x)) throw InputError(std::string(name) + " = " + G(x) + ": must be finite");
  return x;
}

int Integer(const py::handle& v, const char* name) {
  if (py::isinstance<py::bool_>(v) || IsNumpyBool(v) || !py::hasattr(v, "__index__")) {
    throw py::type_error(std::string(name) + " must be an integer, not " + TypeName(v) +
                         (py::hasattr(v, "__float__") ? " (round it: int(round(x)))" : ""));
  }
  const long long x = v.attr("__index__")().cast<long long>();
  if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) {
    throw InputError(std::string(name) + " = " + std::to_string(x) + ": out of range");
  }
  return static_cast<int>(x);
}

std::string PathFrom(const py::handle& p, const char* name) {
  if (!py::isinstance<py::str>(p) && !py::isinstance<py::bytes>(p) && !py::hasattr(p, "__fspath__")) {
    throw py::type_error(std::string(name) + " must be a path (str, bytes or os.PathLike), not " + TypeName(p));
  }
  // Python's own encoding of a file name (a Latin-1 name read by os.listdir comes back as it was).
  const std::string path = py::module_::import("os").attr("fsencode")(p).cast<std::string>();
  return CheckedPath(path, name);
}

const std::string& CheckedPath(const std::string& path, const char* name) {
  if (path.find('\0') != std::string::npos) {  // the C library would stop at it: another file
    throw InputError(std::string(name) + ": the path contains a NUL byte (at " + std::to_string(path.find('\0')) +
                     "); no file name holds one");
  }
  return path;
}

bool SameState(const py::handle& a, const py::handle& b) {
  if (py::isinstance<py::float_>(a) && py::isinstance<py::float_>(b)) {
    const double x = a.cast<double>(), y = b.cast<double>();
    return x == y || (std::isnan(x) && std::isnan(y));
  }
  if ((py::isinstance<py::tuple>(a) && py::isinstance<py::tuple>(b)) ||
      (py::isinstance<py::list>(a) && py::isinstance<py::list>(b))) {
    const py::sequence x = py::reinterpret_borrow<py::sequence>(a), y = py::reinterpret_borrow<py::sequence>(b);
    if (x.size() != y.size()) return false;
    for (size_t i = 0; i < x.size(); ++i) {
      if (!SameState(x[i], y[i])) return false;
    }
    return true;
  }
  return a.equal(b);
}

}  // namespace zwidth::python
