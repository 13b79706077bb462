#include "io/log.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <memory>
#include <sstream>

#include <sys/stat.h>

#include <matio.h>

#include "io/atomic_file.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "io/log_internal.h"
#include "model/error.h"


namespace zwidth::io::internal {
namespace {

// ---- MATLAB .mat (v5 and v7.3, through libmatio) ---------------------------

struct MatCloser { void operator()(mat_t* m) const { if (m) Mat_Close(m); } };
struct VarFree { void operator()(matvar_t* v) const { if (v) Mat_VarFree(v); } };

std::string MatVariables(mat_t* mat) {
  Mat_Rewind(mat);
  std::string list;
  int n = 0;
  while (matvar_t* v = Mat_VarReadNextInfo(mat)) {
    if (n < 12) list += (n ? ", " : "") + std::string(v->name ? v->name : "?").substr(0, 24);
    ++n;
    Mat_VarFree(v);
  }
  if (n > 12) list += ", ...";
  return n ? list : "none";
}

// The variable "name" or the field "name.field" of a struct, as doubles.
// Returns false when it does not exist (and required is false).
bool ReadMatVector(mat_t* mat, const std::string& path, const std::string& spec, const char* flag,
                   std::vector<double>* out) {
  const size_t dot = spec.find('.');
  const std::string var = spec.substr(0, dot);
  std::unique_ptr<matvar_t, VarFree> info(Mat_VarReadInfo(mat, var.c_str()));
  if (!info) return false;
  std::unique_ptr<matvar_t, VarFree> whole(Mat_VarRead(mat, var.c_str()));
  if (!whole) throw InputError(path + ": variable '" + var.substr(0, 40) + "' cannot be read (corrupt file?)");
  matvar_t* v = whole.get();
  if (dot != std::string::npos) {
    if (v->class_type != MAT_C_STRUCT) {
      throw InputError(path + ": '" + var.substr(0, 40) + "' is not a struct; " + flag + " " + spec.substr(0, 40) +
                       " names a field of one");
    }
    v = Mat_VarGetStructFieldByName(v, spec.substr(dot + 1).c_str(), 0);
    if (!v) {
      std::string fields;
      const size_t nf = Mat_VarGetNumberOfFields(whole.get());
      char* const* names = Mat_VarGetStructFieldnames(whole.get());
      for (size_t i = 0; names && i < nf && i < 12; ++i) {
        if (i) fields += ", ";
        fields += std::string(names[i]).substr(0, 24);
      }
      throw InputError(path + ": struct '" + var.substr(0, 40) + "' has no field '" + spec.substr(dot + 1, 40) +
                       "' (fields: " + fields + "); choose one with " + flag);
    }
  }
  size_t n = 1;
  int long_dims = 0;
  for (int i = 0; i < v->rank; ++i) {
    n *= v->dims[i];
    if (v->dims[i] > 1) ++long_dims;
  }
  if (v->isComplex || long_dims > 1 || !v->data) {
    std::string shape;
    for (int i = 0; i < v->rank; ++i) {
      if (i) shape += 'x';
      shape += std::to_string(v->dims[i]);
    }
    throw InputError(path + ": '" + spec.substr(0, 40) + "' is " + (v->isComplex ? "complex " : "") + shape +
                     "; expected a real vector (one signal per variable; save columns as separate variables)");
  }
  out->resize(n);
  auto copy = [&](auto* p) { for (size_t i = 0; i < n; ++i) (*out)[i] = static_cast<double>(p[i]); };
  switch (v->class_type) {
    case MAT_C_DOUBLE: copy(static_cast<const double*>(v->data)); break;
    case MAT_C_SINGLE: copy(static_cast<const float*>(v->data)); break;
    case MAT_C_INT8: copy(static_cast<const int8_t*>(v->data)); break;
    case MAT_C_UINT8: copy(static_cast<const uint8_t*>(v->data)); break;
    case MAT_C_INT16: copy(static_cast<const int16_t*>(v->data)); break;
    case MAT_C_UINT16: copy(static_cast<const uint16_t*>(v->data)); break;
    case MAT_C_INT32: copy(static_cast<const int32_t*>(v->data)); break;
    case MAT_C_UINT32: copy(static_cast<const uint32_t*>(v->data)); break;
    case MAT_C_INT64: copy(static_cast<const int64_t*>(v->data)); break;
    case MAT_C_UINT64: copy(static_cast<const uint64_t*>(v->data)); break;
    default:
      throw InputError(path + ": '" + spec.substr(0, 40) + "' is not numeric (class " +
                       std::to_string(static_cast<int>(v->class_type)) + ")");
  }
  return true;
}

}  // namespace

LogInfo StreamMatInProcess(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  Mat_LogInitFunc("zwidth", [](int, char*) {});  // no stderr chatter from libmatio
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(path + ": cannot open as a MATLAB .mat file (truncated or corrupt?)");
  const char* version = Mat_GetVersion(mat.get()) == MAT_FT_MAT73 ? "v7.3" : "v5";
  std::vector<double> u, y, t;
  auto need = [&](const std::string& spec, const char* flag, std::vector<double>* v) {
    if (!ReadMatVector(mat.get(), path, spec, flag, v)) {
      throw InputError(path + ": no variable '" + spec.substr(0, 40) + "' in this MATLAB " + version +
                       " file (variables: " + MatVariables(mat.get()) + "); choose one with " + flag);
    }
  };
  need(sel.input_column, "LogSelect::input_column", &u);
  need(sel.output_column, "LogSelect::output_column", &y);
  const bool rate_given = sel.sample_rate_hz > 0.0;
  bool have_time = false;
  if (sel.time_column != "none") {
    have_time = ReadMatVector(mat.get(), path, sel.time_column, "LogSelect::time_column", &t);
    if (!have_time && !rate_given) {
      throw InputError(path + ": no time variable '" + sel.time_column.substr(0, 40) + "' (variables: " +
                       MatVariables(mat.get()) + "); choose one with LogSelect::time_column, or pass LogSelect::sample_rate_hz");
    }
  }
  if (u.size() != y.size() || (have_time && t.size() != u.size())) {
    throw InputError(path + ": the variables have different lengths (input " + std::to_string(u.size()) +
                     ", output " + std::to_string(y.size()) + (have_time ? ", time " + std::to_string(t.size()) : "") + ")");
  }
  if (u.empty()) throw InputError(path + ": variable '" + sel.input_column.substr(0, 40) + "' is empty");
  TimeChecker times(path, sel.max_interval_deviation, !rate_given);
  for (size_t i = 0; i < u.size(); ++i) {
    const std::string where = "sample " + std::to_string(i + 1);
    CheckFinite(u[i], path + ":" + sel.input_column, where);
    CheckFinite(y[i], path + ":" + sel.output_column, where);
    if (have_time) {
      CheckFinite(t[i], path + ":" + sel.time_column, where);
      times.Add(t[i], where + " of " + sel.time_column);
    }
  }
  ConstantCheck constant;
  constant.Add(u.data(), u.size());
  if (!constant.varies) {
    throw InputError(path + ": input '" + sel.input_column.substr(0, 40) + "' is constant: no excitation to identify from");
  }
  for (size_t off = 0; off < u.size(); off += kChunk) sink(u.data() + off, y.data() + off, std::min(kChunk, u.size() - off));
  LogInfo info;
  info.source = path;
  info.num_samples = u.size();
  info.sample_rate_hz = rate_given ? sel.sample_rate_hz : times.Rate();
  if (!(info.sample_rate_hz > 0.0) || !std::isfinite(info.sample_rate_hz)) {
    throw InputError(path + ": cannot tell the sample rate (fewer than 2 samples?); pass LogSelect::sample_rate_hz");
  }
  return info;
}

}  // namespace zwidth::io::internal
