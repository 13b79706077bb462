// The MATLAB .mat model export of io/export.cc (v5 or v7.3 through libmatio;
// the variables in docs/export.md); in the plugin zwidth-hdf5.so for the
// zwidth executable (io/hdf5_api.h).
#include <cmath>
#include <complex>
#include <memory>
#include <string>
#include <vector>

#include <matio.h>

#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "model/error.h"
#include "stability/uncertainty.h"

namespace zwidth::io::internal {
namespace {

struct MatCloser { void operator()(mat_t* m) const { if (m) Mat_Close(m); } };

// One file being written; every variable is a double matrix (column-major,
// as MATLAB stores it), a complex column or a char row.
class MatWriter {
 public:
  MatWriter(const std::string& path, bool v73)
      : path_(path), mat_(Mat_CreateVer(path.c_str(), nullptr, v73 ? MAT_FT_MAT73 : MAT_FT_MAT5)) {
    if (!mat_) {
      throw InputError("cannot create the MATLAB file '" + path + "'" +
                       (v73 ? " as v7.3 (this libmatio may lack HDF5 support: export the format mat, v5, instead)" : ""));
    }
  }
  // rows x cols, column-major values.
  void Matrix(const std::string& name, size_t rows, size_t cols, std::vector<double> values) {
    size_t dims[2] = {rows, cols};
    Write(Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, values.data(), 0), name);
  }
  void Scalar(const std::string& name, double v) { Matrix(name, 1, 1, {v}); }
  void Column(const std::string& name, const std::vector<double>& v) { Matrix(name, v.size(), 1, v); }
  void Complex(const std::string& name, const std::vector<std::complex<double>>& h) {
    std::vector<double> re(h.size()), im(h.size());
    for (size_t k = 0; k < h.size(); ++k) { re[k] = h[k].real(); im[k] = h[k].imag(); }
    mat_complex_split_t z{re.data(), im.data()};
    size_t dims[2] = {h.size(), 1};
    Write(Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, &z, MAT_F_COMPLEX), name);
  }
  // A char matrix, one padded row per text (cellstr(x) gives the texts back).
  void Texts(const std::string& name, const std::vector<std::string>& texts) {
    size_t width = 0;
    for (const std::string& t : texts) width = std::max(width, t.size());
    std::vector<char> chars(texts.size() * width, ' ');
    for (size_t r = 0; r < texts.size(); ++r) {
      for (size_t c = 0; c < texts[r].size(); ++c) chars[c * texts.size() + r] = texts[r][c];
    }
    size_t dims[2] = {texts.size(), width};
    Write(Mat_VarCreate(name.c_str(), MAT_C_CHAR, MAT_T_UINT8, 2, dims, chars.data(), 0), name);
  }
  void Close() {
    if (Mat_Close(mat_.release()) != 0) throw InputError("cannot finish writing the MATLAB file '" + path_ + "'");
  }

 private:
  void Write(matvar_t* v, const std::string& name) {
    const bool ok = v && Mat_VarWrite(mat_.get(), v, MAT_COMPRESSION_NONE) == 0;
    if (v) Mat_VarFree(v);
    if (!ok) throw InputError("cannot write variable '" + name + "' to the MATLAB file '" + path_ + "'");
  }
  std::string path_;
  std::unique_ptr<mat_t, MatCloser> mat_;
};

// m, b, omega, c, v, d of `p` as variables named prefix + name.
void Parameters(MatWriter& w, const std::string& prefix, const model::Plant& p) {
  std::vector<double> om, c, v, d;
  for (const model::Mode& md : p.modes) { om.push_back(md.omega); c.push_back(md.c); v.push_back(md.v); d.push_back(md.d); }
  w.Scalar(prefix + "m", p.m);
  w.Scalar(prefix + "b", p.b);
  w.Column(prefix + "omega", om);
  w.Column(prefix + "c", c);
  w.Column(prefix + "v", v);
  w.Column(prefix + "d", d);
}

}  // namespace

void WriteModelMat(const std::string& tmp, const ModelFile& mf, double T, const ident::FrequencyResponse* frf,
                   bool v73) {
  Mat_LogInitFunc("zwidth", [](int, char*) {});  // no stderr chatter from libmatio
  MatWriter w(tmp, v73);
  const model::Plant& p = mf.plant;
  w.Texts("name", {p.name});
  Parameters(w, "", p);
  if (mf.std_errors) Parameters(w, "std_", *mf.std_errors);  // +inf = unknown
  w.Scalar("delay_samples", p.delay_samples);
  if (T > 0) {
    w.Scalar("period_s", T);
    w.Scalar("delay_s", p.delay_samples * T);
  }
  if (mf.friction) {
    for (const auto& [name, v] : FrictionFields(*mf.friction)) w.Scalar("friction_" + name, v);
  }
  if (!mf.log_covariance.empty()) {
    const size_t n = static_cast<size_t>(stability::NumLogParameters(p));
    std::vector<double> cm(n * n);  // row-major in the model -> column-major (symmetric anyway)
    for (size_t r = 0; r < n; ++r) for (size_t c = 0; c < n; ++c) cm[c * n + r] = mf.log_covariance[r * n + c];
    w.Matrix("covariance", n, n, cm);
    w.Texts("covariance_parameters", stability::LogParameterNames(p));
  }
  if (frf) {
    w.Column("f", frf->f_hz);
    w.Complex("H", frf->H);
    w.Column("H_std", frf->H_std);
    w.Column("coherence", frf->coherence);
    w.Scalar("num_averages", frf->num_averages);
    w.Scalar("effective_averages", frf->effective_averages);
    w.Scalar("sample_rate_hz", frf->sample_rate_hz);
  }
  w.Close();
}

}  // namespace zwidth::io::internal
