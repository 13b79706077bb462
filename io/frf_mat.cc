// A frequency response computed in MATLAB or Octave, read from a .mat file
// (v5/v7 and v7.3 through libmatio) for io/frf_file.cc; in the plugin
// zwidth-hdf5.so for the zwidth executable (io/hdf5_api.h). Variables (the
// first name found of each; docs/export.md): f or f_hz [Hz]; H (complex) or
// H_re and H_im; optional H_std or std, coherence or coh, num_averages or
// n_avg, effective_averages, sample_rate_hz or fs.
#include <cmath>
#include <complex>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <matio.h>

#include "io/hdf5_api.h"
#include "model/error.h"

namespace zwidth::io::internal {

void CheckMatV5Variables(const std::string& path, mat_t* mat);  // io/log_mat.cc
std::string MatVariableNames(mat_t* mat);                       // io/log_mat.cc

namespace {

struct MatCloser { void operator()(mat_t* m) const { if (m) Mat_Close(m); } };
struct VarFree { void operator()(matvar_t* v) const { if (v) Mat_VarFree(v); } };

struct Vector {
  bool found = false;
  std::string name;
  std::vector<std::complex<double>> values;
};

// The first of `names` that the file holds, as a real or complex double or
// single vector; InputError for another kind of variable.
Vector Read(mat_t* mat, const std::string& path, std::initializer_list<const char*> names, bool complex_allowed) {
  Vector out;
  for (const char* name : names) {
    std::unique_ptr<matvar_t, VarFree> info(Mat_VarReadInfo(mat, name));
    if (!info) continue;
    std::unique_ptr<matvar_t, VarFree> v(Mat_VarRead(mat, name));
    if (!v) throw InputError(path + ": variable '" + name + "' cannot be read (corrupt file?)");
    size_t n = 1;
    int long_dims = 0;
    for (int i = 0; i < v->rank; ++i) {
      n *= v->dims[i];
      if (v->dims[i] > 1) ++long_dims;
    }
    const bool real_type = v->class_type == MAT_C_DOUBLE || v->class_type == MAT_C_SINGLE;
    if (!real_type || long_dims > 1 || (n && !v->data) || (v->isComplex && !complex_allowed)) {
      throw InputError(path + ": variable '" + std::string(name) + "' must be a " +
                       (complex_allowed ? "" : "real ") + "double vector (one value per frequency bin)");
    }
    if (n > kMaxFrfBins) {
      throw InputError(path + ": variable '" + std::string(name) + "' has " + std::to_string(n) +
                       " values, more than a response has (" + std::to_string(kMaxFrfBins) + ")");
    }
    auto at = [&](const void* p, size_t k) {
      return v->class_type == MAT_C_DOUBLE ? static_cast<const double*>(p)[k]
                                           : static_cast<double>(static_cast<const float*>(p)[k]);
    };
    out.values.resize(n);
    for (size_t k = 0; k < n; ++k) {
      if (v->isComplex) {
        const auto* z = static_cast<const mat_complex_split_t*>(v->data);
        out.values[k] = {at(z->Re, k), at(z->Im, k)};
      } else {
        out.values[k] = at(v->data, k);
      }
      if (!std::isfinite(out.values[k].real()) || !std::isfinite(out.values[k].imag())) {
        throw InputError(path + ": variable '" + std::string(name) + "', value " + std::to_string(k + 1) +
                         " is not finite");
      }
    }
    out.found = true;
    out.name = name;
    return out;
  }
  return out;
}

}  // namespace

std::string ReadFrfMatPacked(const std::string& path) {
  Mat_LogInitFunc("zwidth", [](int, char*) {});
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(path + ": cannot open as a MATLAB .mat file (truncated or corrupt?)");
  if (Mat_GetVersion(mat.get()) == MAT_FT_MAT4) {
    throw InputError(path + ": a MATLAB v4 file (save -v4), which zwidth does not read: save it as v7 (save -v7)");
  }
  if (Mat_GetVersion(mat.get()) != MAT_FT_MAT73) CheckMatV5Variables(path, mat.get());
  const Vector f = Read(mat.get(), path, {"f", "f_hz"}, false);
  Vector h = Read(mat.get(), path, {"H"}, true);
  if (!f.found || (!h.found && !Read(mat.get(), path, {"H_re"}, false).found)) {
    throw InputError(path + ": a frequency response in a .mat file needs f (Hz) and H (complex), or f, H_re and "
                     "H_im (variables: " + MatVariableNames(mat.get()) + ")");
  }
  if (!h.found) {
    const Vector re = Read(mat.get(), path, {"H_re"}, false), im = Read(mat.get(), path, {"H_im"}, false);
    if (!im.found || im.values.size() != re.values.size()) {
      throw InputError(path + ": H_re is given but H_im is not, or their lengths differ");
    }
    h = re;
    for (size_t k = 0; k < h.values.size(); ++k) h.values[k] = {re.values[k].real(), im.values[k].real()};
  }
  const size_t n = f.values.size();
  const Vector sd = Read(mat.get(), path, {"H_std", "std"}, false);
  const Vector coh = Read(mat.get(), path, {"coherence", "coh"}, false);
  for (const Vector* v : {static_cast<const Vector*>(&h), &sd, &coh}) {
    if (v->found && v->values.size() != n) {
      throw InputError(path + ": variable '" + v->name + "' has " + std::to_string(v->values.size()) +
                       " values, f has " + std::to_string(n) + ": they must agree");
    }
  }
  auto scalar = [&](std::initializer_list<const char*> names, double fallback) {
    const Vector v = Read(mat.get(), path, names, false);
    if (!v.found) return fallback;
    if (v.values.size() != 1) throw InputError(path + ": variable '" + v.name + "' must be one number");
    return v.values[0].real();
  };
  // NaN marks a column that is absent: io/frf_file.cc fills it by the rule
  // every response reader shares.
  const double nan = std::nan("");
  std::vector<double> packed = {static_cast<double>(n), scalar({"sample_rate_hz", "fs"}, 0.0),
                                scalar({"num_averages", "n_avg"}, 0.0), scalar({"effective_averages"}, 0.0), 1.0};
  for (size_t k = 0; k < n; ++k) packed.push_back(f.values[k].real());
  for (size_t k = 0; k < n; ++k) packed.push_back(h.values[k].real());
  for (size_t k = 0; k < n; ++k) packed.push_back(h.values[k].imag());
  for (size_t k = 0; k < n; ++k) packed.push_back(coh.found ? coh.values[k].real() : nan);
  for (size_t k = 0; k < n; ++k) packed.push_back(sd.found ? sd.values[k].real() : nan);
  packed.insert(packed.end(), 2 * n, 0.0);  // S_uu, S_yy: unknown
  return std::string(reinterpret_cast<const char*>(packed.data()), packed.size() * sizeof(double));
}

bool HasFrfMatVariables(const std::string& path) {
  Mat_LogInitFunc("zwidth", [](int, char*) {});
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) return false;  // the log reader says why
  auto has = [&](const char* name) { return std::unique_ptr<matvar_t, VarFree>(Mat_VarReadInfo(mat.get(), name)) != nullptr; };
  return (has("f") || has("f_hz")) && (has("H") || has("H_re"));
}

}  // namespace zwidth::io::internal
