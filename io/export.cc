#include "io/export.h"

#include <cmath>
#include <cstdio>
#include <locale>
#include <sstream>

#include "model/units.h"
#include "io/atomic_file.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "io/provenance.h"
#include "model/error.h"
#include "model/state_space.h"
#include "stability/uncertainty.h"

namespace zwidth::io {
namespace {

// Locale-independent (to_chars): embedded in a process whose C locale is
// German (Python after locale.setlocale), "%.17g" wrote m = 0,001168, which
// MATLAB and Octave read as m = 0.
std::string Num(double v) {
  std::string s;
  internal::AppendG(&s, v, 17);
  return s;
}

// A stream that writes numbers the same under any global C++ locale (no
// digit grouping: 1000 stays 1000).
struct ClassicStream : std::ostringstream {
  ClassicStream() { imbue(std::locale::classic()); }
};

// "[a b; c d]" (MATLAB) or "[[a, b], [c, d]]" (Python).
std::string Matrix(const Eigen::MatrixXd& M, bool python) {
  ClassicStream os;
  os << "[";
  for (int i = 0; i < M.rows(); ++i) {
    if (python) os << (i ? ", [" : "[");
    for (int j = 0; j < M.cols(); ++j) os << (j ? (python ? ", " : " ") : "") << Num(M(i, j));
    os << (python ? "]" : (i + 1 < M.rows() ? "; " : ""));
  }
  os << "]";
  return os.str();
}

// True when every byte is printable ASCII (0x20..0x7e).
bool PrintableAscii(const std::string& s) {
  for (unsigned char ch : s) {
    if (ch < 0x20 || ch > 0x7e) return false;
  }
  return true;
}

// A MATLAB/Octave expression whose value is the text s, so that an exported
// .m file only defines data whatever the name holds (issue 11): printable
// ASCII as a single-quoted char literal (quotes doubled; % and \ are plain
// characters there), anything else as its UTF-8 bytes decoded by
// native2unicode (NUL, newlines and non-ASCII included).
std::string MatlabString(const std::string& s) {
  std::string out;
  if (PrintableAscii(s)) {
    out = "'";
    for (char ch : s) out += ch == '\'' ? std::string("''") : std::string(1, ch);
    return out + "'";
  }
  out = "native2unicode(uint8([";
  for (size_t i = 0; i < s.size(); ++i) {
    out += (i ? " " : "") + std::to_string(static_cast<unsigned char>(s[i]));
  }
  return out + "]), 'UTF-8')";
}

// A Python expression whose value is the text s: printable ASCII as a
// double-quoted literal with \ and " escaped; anything else as its bytes
// (\xNN escapes) decoded from UTF-8 (surrogateescape keeps invalid bytes).
std::string PythonString(const std::string& s) {
  std::string out;
  const bool plain = PrintableAscii(s);
  out = plain ? "\"" : "b\"";
  for (unsigned char ch : s) {
    if (ch == '\\' || ch == '"') {
      out += '\\';
      out += static_cast<char>(ch);
    } else if (ch >= 0x20 && ch <= 0x7e) {
      out += static_cast<char>(ch);
    } else {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", ch);
      out += b;
    }
  }
  return out + (plain ? "\"" : "\".decode(\"utf-8\", \"surrogateescape\")");
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

}  // namespace

namespace internal {
std::vector<std::pair<std::string, double>> FrictionFields(const model::Friction& f) {
  return {{"coulomb_pos", f.coulomb_pos}, {"coulomb_neg", f.coulomb_neg}, {"offset", f.offset},
          {"breakaway_pos", f.breakaway_pos}, {"breakaway_neg", f.breakaway_neg}};
}
}  // namespace internal

namespace {

// The friction (model.json "friction") and its std as variables friction_<field>
// and friction_std_<field>, after `comment` (MATLAB "%", Python "#").
std::string FrictionVariables(const ModelFile& mf, const char* comment, const char* end) {
  if (!mf.friction) return "";
  std::ostringstream os;
  os << comment << " Coulomb friction at the input (model.json 'friction', model/friction.h) [input units]\n";
  for (const auto& [name, v] : internal::FrictionFields(*mf.friction)) os << "friction_" << name << " = " << Num(v) << end << "\n";
  if (mf.friction_std) {
    for (const auto& [name, v] : internal::FrictionFields(*mf.friction_std)) {
      os << "friction_std_" << name << " = " << (std::isfinite(v) ? Num(v) : std::string(*comment == '%' ? "Inf" : "float('inf')")) << end << "\n";
    }
  }
  return os.str();
}

// The standard errors (std_m, std_b, std_w1 ... in .m; std_m, std_b,
// std_modes in .py; Inf = unknown) and the covariance of the log parameters
// with its parameter names, after the parameters.
std::string Uncertainty(const ModelFile& mf, bool python) {
  const char* c = python ? "#" : "%";
  const char* end = python ? "" : ";";
  auto num = [&](double v) { return std::isfinite(v) ? Num(v) : std::string(python ? "float('inf')" : "Inf"); };
  ClassicStream os;
  if (mf.std_errors) {
    const model::Plant& s = *mf.std_errors;
    os << c << " standard errors of the fit (same units; Inf = unknown)\n"
       << "std_m = " << num(s.m) << end << "\nstd_b = " << num(s.b) << end << "\n";
    if (python) {
      os << "std_modes = [  # (omega, c, v, d)\n";
      for (const model::Mode& md : s.modes) os << "    (" << num(md.omega) << ", " << num(md.c) << ", " << num(md.v) << ", " << num(md.d) << "),\n";
      os << "]\n";
    }
    for (size_t i = 0; !python && i < s.modes.size(); ++i) {
      const std::string k = std::to_string(i + 1);
      os << "std_w" << k << " = " << num(s.modes[i].omega) << "; std_c" << k << " = " << num(s.modes[i].c) << "; std_v"
         << k << " = " << num(s.modes[i].v) << "; std_d" << k << " = " << num(s.modes[i].d) << ";\n";
    }
  }
  if (!mf.log_covariance.empty()) {
    const std::vector<std::string> names = stability::LogParameterNames(mf.plant);
    const int n = static_cast<int>(names.size());
    const Eigen::MatrixXd C = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        mf.log_covariance.data(), n, n);
    os << c << " covariance of the natural logs of the parameters (relative units), rows and columns in the order\n"
       << c << " of covariance_parameters (model.json 'covariance')\n"
       << "covariance = " << (python ? "np.array(" + Matrix(C, true) + ")" : Matrix(C, false)) << end << "\n"
       << "covariance_parameters = " << (python ? "[" : "{");
    for (int i = 0; i < n; ++i) os << (i ? ", " : "") << (python ? PythonString(names[i]) : MatlabString(names[i]));
    os << (python ? "]" : "}") << end << "\n";
  }
  return os.str();
}

std::string Matlab(const ModelFile& mf, double T) {
  const model::Plant& p = mf.plant;
  const model::UnitLabels& u = model::Units(mf.linear);
  ClassicStream os;
  os << "% zwidth model export for MATLAB or GNU Octave (pkg load control).\n"
     << "% The parameters of eq. (1) as named variables (SI units, rad/s); G(s) built from its\n"
     << "% factored sections as in the paper's appendix. The model's name is in `name`.\n"
     << "name = " << MatlabString(p.name) << ";\n"
     << "m = " << Num(p.m) << ";  % rigid-body inertia [" << u.m << "]\n"
     << "b = " << Num(p.b) << ";  % rigid-body viscous damping [" << u.b << "]\n";
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const model::Mode& md = p.modes[i];
    const std::string k = std::to_string(i + 1);
    os << "w" << k << " = " << Num(md.omega) << "; c" << k << " = " << Num(md.c) << "; v" << k << " = "
       << Num(md.v) << "; d" << k << " = " << Num(md.d) << ";  % section " << k
       << ": pole pair w, its damping c, zero pair v, its damping d [rad/s]\n";
  }
  os << "delay_samples = " << p.delay_samples << ";  % input delay of the sampled model [samples]\n"
     << FrictionVariables(mf, "%", ";") << Uncertainty(mf, false) << "G = tf(1, [m b 0]);\n";
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const std::string k = std::to_string(i + 1);
    os << "G = G * tf(w" << k << "^2 / v" << k << "^2 * [1 d" << k << " v" << k << "^2], [1 c" << k << " w" << k
       << "^2]);\n";
  }
  if (T > 0) {
    os << "T = " << Num(T) << ";  % sample period [s]\n"
       << "Gz = c2d(G, T, 'zoh');\n"
       << "if delay_samples > 0\n  Gz = Gz * tf(1, [1 zeros(1, delay_samples)], T);  % z^-delay_samples\nend\n"
       << "% The loop of the paper's eq. (4) for virtual damping B [" << u.B << "] and loop delay d\n"
       << "% [samples]: T / ((T z^d) / Gz + B (z - 1) / z), i.e. Gz / (z^d + B (1 - z^-1)/T Gz)\n"
       << "% (the appendix's parenthesis corrected). [K_cr, ~, w_cr] = margin(zwidth_loop(B, d)) is the\n"
       << "% appendix's call (f_CR = w_cr / (2 pi)). CAVEAT: margin() reports the -180 deg crossover whose\n"
       << "% gain is nearest 0 dB, which can be a high-frequency one (a lightly damped mode, the delay near\n"
       << "% Nyquist): then it is not the paper's K_CR, which is the smallest positive gain over all -180 deg\n"
       << "% crossings (zwidth's exact K_CR). zwidth_crossings(B, d) below lists every -180 deg crossing\n"
       << "% (from freqresp on a log grid of 20000 frequencies up to Nyquist, interpolated) as rows\n"
       << "% [K f_hz]; the paper's K_CR is the smallest positive K. `zwidth boundary` prints both.\n"
       << "% WARNING: a gain margin is a stability limit only while the loop with K = 0 is stable.\n"
       << "% Past B_max that loop is unstable and margin() still reports a positive K although no\n"
       << "% K is stable: eq. (4)'s margin is not the Z-width there (`zwidth boundary` gives both).\n"
       << "zwidth_z = tf('z', T);\n"
       << "zwidth_loop = @(B, d) T / ((T * zwidth_z^d) / Gz + B * (zwidth_z - 1) / zwidth_z);\n"
       << "zwidth_w = logspace(log10(2 * pi * 0.01), log10(pi / T * (1 - 1e-9)), 20000);\n"
       << "zwidth_h = @(B, d) reshape(freqresp(zwidth_loop(B, d), zwidth_w), 1, []);\n"
       << "zwidth_at = @(h, i) [i; imag(h(i)) ./ (imag(h(i)) - imag(h(i + 1)))];  % bin and fraction of each sign change\n"
       << "zwidth_interp = @(x, i) x(i(1, :)) + i(2, :) .* (x(i(1, :) + 1) - x(i(1, :)));\n"
       << "zwidth_cross = @(h, i) [-1 ./ real(zwidth_interp(h, i)); zwidth_interp(zwidth_w, i) / (2 * pi)].';\n"
       << "zwidth_sign_changes = @(h) find(imag(h(1:end-1)) .* imag(h(2:end)) <= 0);\n"
       << "zwidth_crossings_of = @(h) zwidth_cross(h, zwidth_at(h, zwidth_sign_changes(h)));\n"
       << "zwidth_crossings = @(B, d) zwidth_crossings_of(zwidth_h(B, d));\n";
  }
  return os.str();
}

std::string Python(const ModelFile& mf, double T) {
  const model::Plant& p = mf.plant;
  const model::UnitLabels& u = model::Units(mf.linear);
  const model::StateSpace c = model::ContinuousStateSpace(p);
  ClassicStream os;
  os << "\"\"\"zwidth model export. Needs NumPy and SciPy; python-control objects too when it is installed.\n\n"
     << "name: the model's name. m, b, modes, delay_samples: the parameters of eq. (1).\n"
     << "G: continuous scipy.signal.StateSpace of eq. (1) (a well-conditioned cascade realisation).\n";
  if (T > 0) os << "Gz: its exact ZOH discretisation with dt = T, the input delay realised as states.\n";
  os << (T > 0 ? "G_control, Gz_control: the same systems" : "G_control: the same system")
     << " as python-control StateSpace (when `control` is importable), else None.\n"
     << "\"\"\"\nimport numpy as np\nfrom scipy import signal\n\n"
     << "name = " << PythonString(p.name) << "\n"
     << "m = " << Num(p.m) << "  # " << u.m << "\nb = " << Num(p.b) << "  # " << u.b
     << "\nmodes = [  # (omega, c, v, d) rad/s\n";
  for (const model::Mode& md : p.modes) os << "    (" << Num(md.omega) << ", " << Num(md.c) << ", " << Num(md.v) << ", " << Num(md.d) << "),\n";
  os << "]\ndelay_samples = " << p.delay_samples << "\n" << FrictionVariables(mf, "#", "") << Uncertainty(mf, true) << "\n"
     << "G = signal.StateSpace(np.array(" << Matrix(c.A, true) << "),\n    np.array(" << Matrix(c.B, true)
     << "),\n    np.array(" << Matrix(c.C, true) << "),\n    np.array([[" << Num(c.D) << "]]))\n";
  if (T > 0) {
    const model::StateSpace d = model::WithDelayStates(model::DiscretizeZoh(p, T));
    os << "T = " << Num(T) << "  # s\n"
       << "Gz = signal.StateSpace(np.array(" << Matrix(d.A, true) << "),\n    np.array(" << Matrix(d.B, true)
       << "),\n    np.array(" << Matrix(d.C, true) << "),\n    np.array([[" << Num(d.D) << "]]), dt=T)\n";
  }
  os << "\ntry:\n    import control\nexcept ImportError:\n    control = None\n"
     << "G_control = control.ss(G.A, G.B, G.C, G.D) if control is not None else None\n";
  if (T > 0) os << "Gz_control = control.ss(Gz.A, Gz.B, Gz.C, Gz.D, T) if control is not None else None\n";
  return os.str();
}

nlohmann::json StateSpaceJson(const ModelFile& mf, double T) {
  const model::StateSpace c = model::ContinuousStateSpace(mf.plant);
  nlohmann::json j = {{"continuous", {{"A", MatrixJson(c.A)}, {"B", MatrixJson(c.B)}, {"C", MatrixJson(c.C)}, {"D", c.D}}}};
  if (T > 0) {
    const model::StateSpace d = model::WithDelayStates(model::DiscretizeZoh(mf.plant, T));
    j["discrete"] = {{"A", MatrixJson(d.A)}, {"B", MatrixJson(d.B)}, {"C", MatrixJson(d.C)}, {"D", d.D},
                     {"period_s", T}, {"delay_samples_realised_as_states", mf.plant.delay_samples}};
  }
  j["model"] = ModelToJson(mf);
  j["provenance"] = ProvenanceJson();
  return j;
}

}  // namespace

std::string ToString(ExportFormat f) {
  switch (f) {
    case ExportFormat::kJson: return "json";
    case ExportFormat::kHdf5: return "hdf5";
    case ExportFormat::kMatlab: return "matlab";
    case ExportFormat::kPython: return "python";
    case ExportFormat::kStateSpace: return "statespace";
    case ExportFormat::kMat: return "mat";
    case ExportFormat::kMat73: return "mat73";
  }
  return "?";
}

bool FromString(const std::string& s, ExportFormat* f) {
  for (ExportFormat e : {ExportFormat::kJson, ExportFormat::kHdf5, ExportFormat::kMatlab, ExportFormat::kPython,
                         ExportFormat::kStateSpace, ExportFormat::kMat, ExportFormat::kMat73}) {
    if (s == ToString(e)) { *f = e; return true; }
  }
  return false;
}

std::vector<std::string> ExportExtensions(ExportFormat f) {
  switch (f) {
    case ExportFormat::kJson:
    case ExportFormat::kStateSpace: return {".json"};
    case ExportFormat::kHdf5: return {".h5", ".hdf5", ".he5"};
    case ExportFormat::kMatlab: return {".m"};
    case ExportFormat::kPython: return {".py"};
    case ExportFormat::kMat:
    case ExportFormat::kMat73: return {".mat"};
  }
  return {};
}

void ExportModel(const ModelFile& mf, ExportFormat fmt, double T, const std::string& path,
                 const ident::FrequencyResponse* response) {
  // A name of another format's extension (export --format python -o model.json) is refused.
  CheckOutputKind(path, "the " + ToString(fmt) + " export", ExportExtensions(fmt));
  mf.plant.Validate();
  if (response && fmt != ExportFormat::kMat && fmt != ExportFormat::kMat73) {
    throw InputError("a measured response is exported only in the .mat formats (the formats mat and mat73), not " +
                     ToString(fmt));
  }
  switch (fmt) {
    case ExportFormat::kJson: WriteModelJson(path, mf); break;
    case ExportFormat::kMatlab: WriteTextAtomically(path, Matlab(mf, T)); break;
    case ExportFormat::kPython: WriteTextAtomically(path, Python(mf, T)); break;
    case ExportFormat::kStateSpace: WriteTextAtomically(path, StateSpaceJson(mf, T).dump(2) + "\n"); break;
    case ExportFormat::kHdf5:
      internal::WriteHdf5Atomically(path, [&](const internal::Hdf5Api& h5, const std::string& tmp) {
        h5.write_model_hdf5(tmp, mf, T);
      });
      break;
    case ExportFormat::kMat:
    case ExportFormat::kMat73:
      internal::WriteHdf5Atomically(path, [&](const internal::Hdf5Api& h5, const std::string& tmp) {
        h5.write_model_mat(tmp, mf, T, response, fmt == ExportFormat::kMat73);
      });
      break;
  }
}

}  // namespace zwidth::io
