#include "io/export.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <H5Cpp.h>

#include "io/atomic_file.h"
#include "model/error.h"
#include "model/state_space.h"

namespace zwidth::io {
namespace {

std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// "[a b; c d]" (MATLAB) or "[[a, b], [c, d]]" (Python).
std::string Matrix(const Eigen::MatrixXd& M, bool python) {
  std::ostringstream os;
  os << "[";
  for (int i = 0; i < M.rows(); ++i) {
    if (python) os << (i ? ", [" : "[");
    for (int j = 0; j < M.cols(); ++j) os << (j ? (python ? ", " : " ") : "") << Num(M(i, j));
    os << (python ? "]" : (i + 1 < M.rows() ? "; " : ""));
  }
  os << "]";
  return os.str();
}

nlohmann::json MatrixJson(const Eigen::MatrixXd& M) {
  nlohmann::json j = nlohmann::json::array();
  for (int i = 0; i < M.rows(); ++i) {
    nlohmann::json r = nlohmann::json::array();
    for (int k = 0; k < M.cols(); ++k) r.push_back(M(i, k));
    j.push_back(r);
  }
  return j;
}

std::string Matlab(const ModelFile& mf, double T) {
  const Plant& p = mf.plant;
  std::ostringstream os;
  os << "% zwidth model export: " << p.name << "\n% G(s) of eq. (1), built from its factored sections as in the paper's appendix.\n"
     << "m = " << Num(p.m) << ";  % kg m^2\nb = " << Num(p.b) << ";  % N m s/rad\n"
     << "G = tf(1, [m b 0]);\n";
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const Mode& md = p.modes[i];
    os << "G = G * tf(" << Num(md.omega * md.omega / (md.v * md.v)) << " * [1 " << Num(md.d) << " " << Num(md.v * md.v)
       << "], [1 " << Num(md.c) << " " << Num(md.omega * md.omega) << "]);  % section " << i + 1 << "\n";
  }
  if (T > 0) {
    os << "T = " << Num(T) << ";  % s\nGz = c2d(G, T, 'zoh');\n";
    if (p.delay_samples > 0) {
      os << "Gz = Gz * tf(1, [1 zeros(1, " << p.delay_samples << ")], T);  % input delay of " << p.delay_samples << " samples\n";
    }
  }
  return os.str();
}

std::string Python(const ModelFile& mf, double T) {
  const Plant& p = mf.plant;
  const StateSpace c = ContinuousStateSpace(p);
  std::ostringstream os;
  os << "\"\"\"zwidth model export: " << p.name << ". Needs NumPy and SciPy only.\n\n"
     << "G: continuous scipy.signal.StateSpace of eq. (1) (a well-conditioned cascade realisation).\n";
  if (T > 0) os << "Gz: its exact ZOH discretisation with dt = T, the input delay realised as states.\n";
  os << "\"\"\"\nimport numpy as np\nfrom scipy import signal\n\n"
     << "m = " << Num(p.m) << "  # kg m^2\nb = " << Num(p.b) << "  # N m s/rad\nmodes = [  # (omega, c, v, d) rad/s\n";
  for (const Mode& md : p.modes) os << "    (" << Num(md.omega) << ", " << Num(md.c) << ", " << Num(md.v) << ", " << Num(md.d) << "),\n";
  os << "]\ndelay_samples = " << p.delay_samples << "\n\n"
     << "G = signal.StateSpace(np.array(" << Matrix(c.A, true) << "),\n    np.array(" << Matrix(c.B, true)
     << "),\n    np.array(" << Matrix(c.C, true) << "),\n    np.array([[" << Num(c.D) << "]]))\n";
  if (T > 0) {
    const StateSpace d = WithDelayStates(DiscretizeZoh(p, T));
    os << "T = " << Num(T) << "  # s\n"
       << "Gz = signal.StateSpace(np.array(" << Matrix(d.A, true) << "),\n    np.array(" << Matrix(d.B, true)
       << "),\n    np.array(" << Matrix(d.C, true) << "),\n    np.array([[" << Num(d.D) << "]]), dt=T)\n";
  }
  return os.str();
}

nlohmann::json StateSpaceJson(const ModelFile& mf, double T) {
  const StateSpace c = ContinuousStateSpace(mf.plant);
  nlohmann::json j = {{"continuous", {{"A", MatrixJson(c.A)}, {"B", MatrixJson(c.B)}, {"C", MatrixJson(c.C)}, {"D", c.D}}}};
  if (T > 0) {
    const StateSpace d = WithDelayStates(DiscretizeZoh(mf.plant, T));
    j["discrete"] = {{"A", MatrixJson(d.A)}, {"B", MatrixJson(d.B)}, {"C", MatrixJson(d.C)}, {"D", d.D},
                     {"period_s", T}, {"delay_samples_realised_as_states", mf.plant.delay_samples}};
  }
  j["model"] = ModelToJson(mf);
  return j;
}

void WriteH5(const std::string& tmp, const ModelFile& mf, double T) {
  H5::Exception::dontPrint();
  try {
    H5::H5File f(tmp, H5F_ACC_TRUNC);
    auto vec = [&](H5::Group& g, const std::string& name, const std::vector<double>& v) {
      const hsize_t n = v.size();
      H5::DataSpace sp(1, &n);
      H5::DataSet ds = g.createDataSet(name, H5::PredType::IEEE_F64LE, sp);
      if (n) ds.write(v.data(), H5::PredType::NATIVE_DOUBLE);
    };
    auto mat = [&](H5::Group& g, const std::string& name, const Eigen::MatrixXd& M) {
      const hsize_t dims[2] = {static_cast<hsize_t>(M.rows()), static_cast<hsize_t>(M.cols())};
      H5::DataSpace sp(2, dims);
      H5::DataSet ds = g.createDataSet(name, H5::PredType::IEEE_F64LE, sp);
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> R = M;
      ds.write(R.data(), H5::PredType::NATIVE_DOUBLE);
    };
    auto params = [&](const std::string& gname, const Plant& p) {
      H5::Group g = f.createGroup(gname);
      vec(g, "m", {p.m});
      vec(g, "b", {p.b});
      std::vector<double> w, c, v, d;
      for (const Mode& md : p.modes) { w.push_back(md.omega); c.push_back(md.c); v.push_back(md.v); d.push_back(md.d); }
      vec(g, "omega", w); vec(g, "c", c); vec(g, "v", v); vec(g, "d", d);
    };
    params("/parameters", mf.plant);
    if (mf.std_errors) params("/std", *mf.std_errors);
    const StateSpace c = ContinuousStateSpace(mf.plant);
    H5::Group gc = f.createGroup("/continuous");
    mat(gc, "A", c.A); mat(gc, "B", c.B); mat(gc, "C", c.C); mat(gc, "D", Eigen::MatrixXd::Constant(1, 1, c.D));
    H5::Group root = f.openGroup("/");
    auto attr = [&](H5::Group& g, const char* name, double v) {
      H5::Attribute a = g.createAttribute(name, H5::PredType::IEEE_F64LE, H5::DataSpace(H5S_SCALAR));
      a.write(H5::PredType::NATIVE_DOUBLE, &v);
    };
    attr(root, "delay_samples", mf.plant.delay_samples);
    if (T > 0) {
      const StateSpace d = WithDelayStates(DiscretizeZoh(mf.plant, T));
      H5::Group gd = f.createGroup("/discrete");
      mat(gd, "A", d.A); mat(gd, "B", d.B); mat(gd, "C", d.C); mat(gd, "D", Eigen::MatrixXd::Constant(1, 1, d.D));
      attr(gd, "period_s", T);
    }
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
}

}  // namespace

std::string ToString(ExportFormat f) {
  switch (f) {
    case ExportFormat::kJson: return "json";
    case ExportFormat::kHdf5: return "hdf5";
    case ExportFormat::kMatlab: return "matlab";
    case ExportFormat::kPython: return "python";
    case ExportFormat::kStateSpace: return "statespace";
  }
  return "?";
}

bool FromString(const std::string& s, ExportFormat* f) {
  for (ExportFormat e : {ExportFormat::kJson, ExportFormat::kHdf5, ExportFormat::kMatlab, ExportFormat::kPython,
                         ExportFormat::kStateSpace}) {
    if (s == ToString(e)) { *f = e; return true; }
  }
  return false;
}

void ExportModel(const ModelFile& mf, ExportFormat fmt, double T, const std::string& path) {
  mf.plant.Validate();
  switch (fmt) {
    case ExportFormat::kJson: WriteTextAtomically(path, ModelToJson(mf).dump(2) + "\n"); break;
    case ExportFormat::kMatlab: WriteTextAtomically(path, Matlab(mf, T)); break;
    case ExportFormat::kPython: WriteTextAtomically(path, Python(mf, T)); break;
    case ExportFormat::kStateSpace: WriteTextAtomically(path, StateSpaceJson(mf, T).dump(2) + "\n"); break;
    case ExportFormat::kHdf5: WriteAtomically(path, [&](const std::string& tmp) { WriteH5(tmp, mf, T); }); break;
  }
}

}  // namespace zwidth::io
