// The Python module zwidth._zwidth (imported by the package zwidth, see
// python/zwidth/__init__.py). Errors: InputError -> zwidth.InputError (a
// ValueError), ComputationError -> zwidth.ComputationError (a RuntimeError),
// with the library's messages, which are the CLI's.
#include <cmath>


#include "build_info.h"
#include "io/model_json.h"
#include "io/option_names.h"
#include "model/cancel.h"
#include "model/error.h"
#include "model/parallel.h"
#include "python/bind_common.h"

namespace zwidth::python {

py::object JsonToPython(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& e : j) l.append(JsonToPython(e));
      return l;
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = JsonToPython(it.value());
      return d;
    }
    default: return py::none();
  }
}

double ResolvePeriod(const std::optional<double>& period_s, io::ModelFile* model) {
  std::string note;
  const double T = io::ResolveModelPeriod(period_s, model, &note);
  if (!note.empty() && PyErr_WarnEx(PyExc_UserWarning, io::WithKeywords(note).c_str(), 1) != 0) {
    throw py::error_already_set();  // warnings configured as errors
  }
  return T;
}

namespace {

unsigned long g_main_thread = 0;  // threading.main_thread().ident: Python handles signals there
PyObject* g_pending[3] = {nullptr, nullptr, nullptr};  // the exception a signal handler raised

// zwidth::PollCancel's check (model/cancel.h): on the main thread, runs Python's
// signal handlers (PyErr_CheckSignals, under the GIL); a handler that raised
// (Ctrl-C: KeyboardInterrupt) stops the computation, and its exception is
// kept for the translator below to raise when the call unwinds.
bool PythonSignalRaised() {
  if (PyThread_get_thread_ident() != g_main_thread) return false;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  if (!g_pending[0]) PyErr_Fetch(&g_pending[0], &g_pending[1], &g_pending[2]);
  PyErr_Clear();
  return true;
}

void RaiseCancelled() {
  ClearCancel();
  if (g_pending[0]) {
    PyErr_Restore(g_pending[0], g_pending[1], g_pending[2]);
    g_pending[0] = g_pending[1] = g_pending[2] = nullptr;
  } else {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
  }
}

}  // namespace

}  // namespace zwidth::python

namespace zwidth::python {
void BindBatch(py::module_& m);  // zwidth.batch's units in this process (bind_batch.cc)
}  // namespace zwidth::python

PYBIND11_MODULE(_zwidth, m) {
  namespace py = pybind11;
  using namespace zwidth::python;
  m.doc() = "zwidth: haptic device identification and Z-width (compiled core; use the package zwidth)";
  // The library's errors with the keywords where it names option fields (io/option_names.h).
  static py::exception<zwidth::InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<zwidth::ComputationError> computation_error(m, "ComputationError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const zwidth::InputError& e) {
      PyErr_SetString(input_error.ptr(), zwidth::io::WithKeywords(e.what()).c_str());
    } catch (const zwidth::ComputationError& e) {
      PyErr_SetString(computation_error.ptr(), zwidth::io::WithKeywords(e.what()).c_str());
    } catch (const zwidth::Cancelled&) {
      RaiseCancelled();
    }
  });
  g_main_thread = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  zwidth::SetCancelCheck(&PythonSignalRaised);
  m.def("set_num_threads", [](const py::object& n) { zwidth::SetNumThreads(n.is_none() ? 0 : Integer(n, "n")); },
        py::arg("n"),
        "Threads of the parallel parts (fit starts, per-delay summaries, boundary rows): n >= 1, or None for "
        "the default (the environment's ZWIDTH_NUM_THREADS, else the cores this process may use: affinity and "
        "cgroup quota).", kCLocale);
  m.def("num_threads", &zwidth::NumThreads, "The threads a parallel part uses now (see set_num_threads).", kCLocale);
  m.attr("InputError").attr("__module__") = "zwidth";
  m.attr("ComputationError").attr("__module__") = "zwidth";
  m.attr("InputError").attr("__doc__") =
      "Bad input (a file, a field, an option): the message says what, where and what to do. "
      "The CLI exits with 2 for these.";
  m.attr("ComputationError").attr("__doc__") =
      "A computation that failed on valid input (e.g. a relay loop that did not oscillate). "
      "The CLI exits with 1 for these.";
  m.attr("__version__") = zwidth::build_info::kVersion;
  py::dict info;
  info["zwidth"] = zwidth::build_info::kVersion;
  info["ceres"] = zwidth::build_info::kCeres;
  info["eigen"] = zwidth::build_info::kEigen;
  info["fftw"] = zwidth::build_info::kFftw;
  info["hdf5"] = zwidth::build_info::kHdf5;
  info["cli11"] = zwidth::build_info::kCli11;
  info["nlohmann_json"] = zwidth::build_info::kNlohmannJson;
  info["pybind11"] = zwidth::build_info::kPybind11;
  m.attr("_build_info") = info;
  m.def("_last_cpp_seconds", [] { return zwidth::python::g_last_cpp_seconds; },
        "Seconds the last fit() or ZWidth.critical() spent in the C++ library (for bench/python_overhead.py).", kCLocale);
  BindModel(m);
  BindIdent(m);
  BindFit(m);
  BindStability(m);
  BindRun(m);
  BindBatch(m);
}
