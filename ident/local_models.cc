#include "ident/local_models.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include <Eigen/Dense>
#include <fftw3.h>

#include "ident/fft_internal.h"
#include "model/error.h"
#include "model/parallel.h"

namespace zwidth::ident {

using cd = std::complex<double>;

std::string ToString(LocalMethod m) { return m == LocalMethod::kPolynomial ? "lpm" : "lrm"; }

bool FromString(const std::string& s, LocalMethod* m) {
  if (s == "lpm") *m = LocalMethod::kPolynomial;
  else if (s == "lrm") *m = LocalMethod::kRational;
  else return false;
  return true;
}

int LocalModelOptions::HalfWidth() const {
  if (half_width > 0) return half_width;
  return method == LocalMethod::kPolynomial ? 6 : 7;
}

int LocalModelOptions::NumParameters(int runs) const {
  const int g = order + 1, t = order + 1;
  return g + runs * t + (method == LocalMethod::kRational ? denominator_order : 0);
}

bool LocalModelOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (half_width < 0 || half_width > 1000) return fail("LocalModelOptions::half_width = " + std::to_string(half_width) + ": must be in [0, 1000] (0: the method's default)");
  if (order < 0 || order > 6) return fail("LocalModelOptions::order = " + std::to_string(order) + ": must be in [0, 6]");
  if (method == LocalMethod::kRational && (denominator_order < 1 || denominator_order > 6)) {
    return fail("LocalModelOptions::denominator_order = " + std::to_string(denominator_order) + ": must be in [1, 6]");
  }
  if (differences < 0 || differences > 2) return fail("LocalModelOptions::differences = " + std::to_string(differences) + ": must be 0, 1 or 2");
  if (!(fmin_hz >= 0.0) || !std::isfinite(fmin_hz)) return fail("LocalModelOptions::fmin_hz must be finite and >= 0");
  if (!(fmax_hz > fmin_hz)) return fail("LocalModelOptions::fmax_hz must be > LocalModelOptions::fmin_hz");
  const int W = 2 * HalfWidth() + 1, p = NumParameters(1);
  if (W - p < 1) {
    return fail("LocalModelOptions::half_width = " + std::to_string(HalfWidth()) + " gives " + std::to_string(W) +
                " bins for " + std::to_string(p) + " unknowns: no degree of freedom is left for the noise; use at least " +
                std::to_string(p / 2 + 1));
  }
  return true;
}

namespace {

// The spectra of one run: the input X (u, or r in closed loop) and the raw u,
// y over samples d..N-1, and each channel's differenced output Z (y; or u, y
// in closed loop), all of N' = N - d points.
struct RunDft {
  std::vector<cd> x, u, y;
  std::vector<std::vector<cd>> z;
};

std::vector<cd> Dft(const double* v, int n) {
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  std::copy(v, v + n, in);
  fftw_execute_dft_r2c(internal::PlanCache::Get().For(n, in, out), in, out);
  std::vector<cd> r(n / 2 + 1);
  for (int k = 0; k <= n / 2; ++k) r[k] = cd(out[k][0], out[k][1]);
  fftw_free(in);
  fftw_free(out);
  return r;
}

// (1 - z^-1)^d applied to v inside the record: t = d..N-1.
std::vector<double> Difference(const std::vector<double>& v, int d) {
  std::vector<double> w(v.begin() + d, v.end());
  for (size_t t = 0; t < w.size(); ++t) {
    const size_t i = t + d;
    if (d == 1) w[t] = v[i] - v[i - 1];
    if (d == 2) w[t] = v[i] - 2.0 * v[i - 1] + v[i - 2];
  }
  return w;
}

RunDft TransformRun(const LocalRecord& run, size_t n, int d) {
  auto cut = [&](const std::vector<double>& v) { return std::vector<double>(v.begin(), v.begin() + n); };
  const std::vector<double> u = cut(run.u), y = cut(run.y);
  const int np = static_cast<int>(n) - d;
  RunDft s;
  s.u = Dft(u.data() + d, np);
  s.y = Dft(y.data() + d, np);
  if (run.r.empty()) {
    s.x = s.u;
    s.z.push_back(Dft(Difference(y, d).data(), np));
  } else {
    s.x = Dft(cut(run.r).data() + d, np);
    s.z.push_back(Dft(Difference(u, d).data(), np));
    s.z.push_back(Dft(Difference(y, d).data(), np));
  }
  return s;
}

// One channel's local least squares at one bin.
struct ChannelFit {
  cd g = 0.0;                  // G' at the bin (of the differenced output)
  std::vector<cd> c;           // G' = sum_j c_j a_j over the rows a (run-major)
  std::vector<cd> e;           // residuals of the rows
  double transient_ratio = 0.0;
  double q_eff = 0.0;          // the residual's degrees of freedom in units of sigma^2
  bool ok = false;
};

// The geometry shared by every channel of one bin.
struct LocalWindow {
  int k = 0, start = 0, W = 0, q = 0, np = 0;  // bin, first bin, bins, residual dof, DFT length
  std::vector<double> row_weight;  // 1 / |1 - e^{-j theta_j}|^d
};

ChannelFit SolveChannel(const std::vector<RunDft>& runs, int channel, const LocalWindow& w, const LocalModelOptions& o) {
  const int M = static_cast<int>(runs.size()), R = o.order, n = o.HalfWidth();
  const bool rational = o.method == LocalMethod::kRational;
  const int rows = M * w.W, p = o.NumParameters(M);
  Eigen::MatrixXcd K = Eigen::MatrixXcd::Zero(rows, p);
  Eigen::VectorXcd a(rows);
  for (int i = 0; i < M; ++i) {
    for (int jj = 0; jj < w.W; ++jj) {
      const int j = w.start + jj, row = i * w.W + jj;
      const double rr = static_cast<double>(j - w.k) / n, wt = w.row_weight[jj];
      a(row) = runs[i].z[channel][j] * wt;
      double pw = 1.0;
      for (int s = 0; s <= R; ++s, pw *= rr) {
        K(row, s) = runs[i].x[j] * (wt * pw);
        K(row, (R + 1) * (1 + i) + s) = wt * pw;
      }
      if (rational) {
        pw = rr;
        for (int s = 1; s <= o.denominator_order; ++s, pw *= rr) K(row, (R + 1) * (1 + M) + s - 1) = -a(row) * pw;
      }
    }
  }
  ChannelFit f;
  Eigen::VectorXd norm = K.colwise().norm();
  if (!(norm.minCoeff() > 0.0) || !norm.allFinite()) return f;
  for (int c = 0; c < p; ++c) K.col(c) /= norm(c);
  const Eigen::HouseholderQR<Eigen::MatrixXcd> qr(K);
  const auto Rm = qr.matrixQR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::VectorXcd theta = qr.solve(a);
  const Eigen::VectorXd diag = qr.matrixQR().diagonal().cwiseAbs();
  if (!(diag.minCoeff() > 1e-10 * diag.maxCoeff()) || !theta.allFinite()) return f;
  Eigen::VectorXcd e0 = Eigen::VectorXcd::Zero(p);
  e0(0) = 1.0;
  const Eigen::VectorXcd h = qr.matrixQR().topLeftCorner(p, p).adjoint().triangularView<Eigen::Lower>().solve(e0);
  const Eigen::VectorXcd qh = K * Rm.solve(h);
  const Eigen::VectorXcd e = a - K * theta;
  const Eigen::MatrixXcd Q = qr.householderQ() * Eigen::MatrixXcd::Identity(rows, p);
  f.g = theta(0) / norm(0);
  f.c.resize(rows);
  f.e.assign(e.data(), e.data() + rows);
  // Row j's error is D(r_j) V_j (the LRM's equations are multiplied by D; D = 1
  // for the LPM): G' - G = sum_j c_j D(r_j) V_j, and the residual's expected
  // square is sigma^2 sum_j (1 - P_jj) |D(r_j)|^2 (P the hat matrix), which
  // makes the degrees of freedom q_eff.
  f.q_eff = 0.0;
  for (int i = 0; i < M; ++i) {
    for (int jj = 0; jj < w.W; ++jj) {
      const int row = i * w.W + jj;
      const double rr = static_cast<double>(w.start + jj - w.k) / n;
      cd D = 1.0, pw = rr;
      if (rational) {
        for (int s = 1; s <= o.denominator_order; ++s, pw *= rr) {
          const int col = (R + 1) * (1 + M) + s - 1;
          D += theta(col) / norm(col) * pw;
        }
      }
      f.c[row] = std::conj(qh(row)) / norm(0) * D;
      f.q_eff += std::max(0.0, 1.0 - Q.row(row).squaredNorm()) * std::norm(D);
    }
  }
  for (int i = 0; i < M; ++i) {
    const cd t = theta((R + 1) * (1 + i)) / norm((R + 1) * (1 + i));
    const double resp = std::abs(f.g * runs[i].x[w.k]);
    f.transient_ratio = std::max(f.transient_ratio, resp > 0 ? std::abs(t) / resp : 0.0);
  }
  f.ok = true;
  return f;
}

// The estimate at one bin: G, its error as a linear functional of the
// channels' row noise (alpha[channel][row]) and the channels' noise
// covariance Sigma.
struct BinEstimate {
  cd H = 0.0;
  double var = 0.0, coherence = 0.0, transient_ratio = 0.0;
  double suu = 0.0, syy = 0.0;
  cd suy = 0.0;
  std::vector<std::vector<cd>> alpha;
  Eigen::Matrix2cd sigma = Eigen::Matrix2cd::Zero();
  int start = 0;
  bool ok = false;
};

// sum_{c,c'} Sigma_cc' sum_j a_c(j) conj(b_c'(j)) over the rows the windows share
// (b's window starts `shift` bins later).
cd Covariance(const BinEstimate& a, const BinEstimate& b, const Eigen::Matrix2cd& sigma, int W, int M) {
  const int shift = b.start - a.start;
  cd s = 0.0;
  for (size_t c = 0; c < a.alpha.size(); ++c) {
    for (size_t c2 = 0; c2 < b.alpha.size(); ++c2) {
      cd t = 0.0;
      for (int i = 0; i < M; ++i) {
        for (int jj = std::max(0, shift); jj < W && jj - shift < W; ++jj) {
          t += a.alpha[c][i * W + jj] * std::conj(b.alpha[c2][i * W + jj - shift]);
        }
      }
      s += sigma(c, c2) * t;
    }
  }
  return s;
}

BinEstimate EstimateBin(const std::vector<RunDft>& runs, const LocalWindow& w, double psd_scale,
                        const LocalModelOptions& o) {
  const int M = static_cast<int>(runs.size()), channels = static_cast<int>(runs[0].z.size());
  BinEstimate b;
  b.start = w.start;
  std::vector<ChannelFit> f;
  for (int c = 0; c < channels; ++c) {
    f.push_back(SolveChannel(runs, c, w, o));
    if (!f.back().ok || !(f.back().q_eff > 0.0)) return b;
  }
  for (int c = 0; c < channels; ++c) {
    for (int c2 = 0; c2 < channels; ++c2) {
      cd s = 0.0;
      for (size_t r = 0; r < f[c].e.size(); ++r) s += f[c].e[r] * std::conj(f[c2].e[r]);
      b.sigma(c, c2) = s / std::sqrt(f[c].q_eff * f[c2].q_eff);
    }
  }
  double xx = 0.0;
  for (int i = 0; i < M; ++i) {
    for (int jj = 0; jj < w.W; ++jj) {
      const int j = w.start + jj;
      b.suu += std::norm(runs[i].u[j]);
      b.syy += std::norm(runs[i].y[j]);
      b.suy += std::conj(runs[i].u[j]) * runs[i].y[j];
      xx += std::norm(runs[i].x[j]);
    }
  }
  const double count = static_cast<double>(M * w.W);
  b.suu *= psd_scale / count;
  b.syy *= psd_scale / count;
  b.suy *= psd_scale / count;
  xx /= count;
  const double theta = 2.0 * std::numbers::pi * w.k / w.np;
  const cd D = std::pow(1.0 - std::exp(cd(0.0, -theta)), o.differences);
  b.alpha.resize(channels);
  if (channels == 1) {
    b.H = f[0].g / D;
    for (const cd& c : f[0].c) b.alpha[0].push_back(c / D);
    b.transient_ratio = f[0].transient_ratio;
  } else {  // closed loop: G = G'_ry / G'_ru (the differences cancel)
    b.H = f[1].g / f[0].g;
    for (const cd& c : f[0].c) b.alpha[0].push_back(-b.H * c / f[0].g);
    for (const cd& c : f[1].c) b.alpha[1].push_back(c / f[0].g);
    b.transient_ratio = f[1].transient_ratio;
  }
  b.var = std::max(0.0, Covariance(b, b, b.sigma, w.W, M).real());
  const double signal = std::norm(f[channels - 1].g / D) * xx, noise = b.sigma(channels - 1, channels - 1).real();
  b.coherence = signal + noise > 0 ? signal / (signal + noise) : 0.0;
  b.ok = std::isfinite(b.H.real()) && std::isfinite(b.H.imag()) && std::isfinite(b.var);
  return b;
}

// Runs cut to the shortest; throws InputError when a run's u, y (and r) differ
// in length or the record is too short for the window.
size_t CommonLength(const std::vector<LocalRecord>& runs, const LocalModelOptions& o, std::vector<std::string>* warnings) {
  if (runs.empty()) throw InputError("no run to estimate from");
  const bool closed = !runs[0].r.empty();
  size_t n = runs[0].u.size();
  for (size_t i = 0; i < runs.size(); ++i) {
    const LocalRecord& r = runs[i];
    if (r.y.size() != r.u.size() || (!r.r.empty() && r.r.size() != r.u.size())) {
      throw InputError("run " + std::to_string(i + 1) + ": the input, output (and excitation) have different lengths");
    }
    if (r.r.empty() == closed) {
      throw InputError("run " + std::to_string(i + 1) + (closed ? " lacks" : " has") + " an excitation where run 1 " +
                       (closed ? "has one" : "does not"));
    }
    n = std::min(n, r.u.size());
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].u.size() > n) {
      warnings->push_back("run " + std::to_string(i + 1) + ": the last " + std::to_string(runs[i].u.size() - n) +
                          " samples are not used (the local methods need runs of one length: the shortest's, " +
                          std::to_string(n) + ")");
    }
  }
  const int W = 2 * o.HalfWidth() + 1;
  const size_t needed = 2 * static_cast<size_t>(W + 1) + 1 + o.differences;
  if (n < needed) {
    throw InputError("the log has " + std::to_string(n) + " samples, too few for a local window of " + std::to_string(W) +
                     " bins (at least " + std::to_string(needed) +
                     " samples); record a longer log or lower LocalModelOptions::half_width");
  }
  return n;
}

// Mean over the bins of the correlation of the errors at lags 1..2n.
std::vector<cd> ErrorCorrelation(const std::vector<BinEstimate>& bins, int W, int M) {
  const int L = W - 1;
  std::vector<cd> rho(L, 0.0);
  for (int l = 1; l <= L; ++l) {
    cd sum = 0.0;
    int count = 0;
    for (size_t k = 0; k + l < bins.size(); ++k) {
      const BinEstimate& a = bins[k];
      const BinEstimate& b = bins[k + l];
      if (!a.ok || !b.ok || b.start - a.start >= W) continue;
      const double va = a.var, vb = Covariance(b, b, a.sigma, W, M).real();
      if (!(va > 0.0 && vb > 0.0)) continue;
      sum += Covariance(a, b, a.sigma, W, M) / std::sqrt(va * vb);
      ++count;
    }
    rho[l - 1] = count > 0 ? sum / static_cast<double>(count) : 0.0;
  }
  return rho;
}

}  // namespace

LocalEstimate EstimateLocal(const std::vector<LocalRecord>& runs, double fs, const LocalModelOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  if (!(fs > 0.0) || !std::isfinite(fs)) throw InputError("sample rate must be finite and > 0");
  LocalEstimate out;
  const size_t n = CommonLength(runs, o, &out.warnings);
  const int M = static_cast<int>(runs.size()), d = o.differences, np = static_cast<int>(n) - d;
  std::vector<RunDft> dft(runs.size());
  ParallelFor(runs.size(), [&](size_t i) { dft[i] = TransformRun(runs[i], n, d); });
  const int hw = o.HalfWidth(), W = 2 * hw + 1, kmax = (np - 1) / 2;
  const double df = fs / np, fmax = std::min(o.fmax_hz, 0.5 * fs);
  std::vector<int> ks;
  for (int k = 1; k <= kmax; ++k) {
    if (k * df >= o.fmin_hz - 1e-9 * df && k * df <= fmax + 1e-9 * df) ks.push_back(k);
  }
  if (ks.empty()) {
    throw InputError("no frequency bin between LocalModelOptions::fmin_hz and LocalModelOptions::fmax_hz (bin spacing " +
                     std::to_string(df) + " Hz)");
  }
  out.residual_dof = M * W - o.NumParameters(M);
  out.samples_per_run = static_cast<int>(n);
  std::vector<BinEstimate> bins(ks.size());
  const size_t chunk = 256;
  ParallelFor((ks.size() + chunk - 1) / chunk, [&](size_t c) {
    LocalWindow w;
    w.W = W;
    w.q = out.residual_dof;
    w.np = np;
    w.row_weight.resize(W);
    for (size_t i = c * chunk; i < std::min(ks.size(), (c + 1) * chunk); ++i) {
      w.k = ks[i];
      w.start = std::clamp(w.k - hw, 1, kmax - W + 1);
      for (int jj = 0; jj < W; ++jj) {
        const double th = 2.0 * std::numbers::pi * (w.start + jj) / np;
        w.row_weight[jj] = 1.0 / std::pow(std::abs(1.0 - std::exp(cd(0.0, -th))), d);
      }
      bins[i] = EstimateBin(dft, w, 2.0 / (fs * np), o);
    }
  });
  FrequencyResponse& r = out.frf;
  r.sample_rate_hz = fs;
  r.window_length = static_cast<int>(n);
  r.num_averages = out.residual_dof;
  r.effective_averages = out.residual_dof;
  r.estimator = ToString(o.method) + (runs[0].r.empty() ? "" : "-joint");
  for (size_t i = 0; i < ks.size(); ++i) {
    const BinEstimate& b = bins[i];
    r.f_hz.push_back(ks[i] * df);
    r.H.push_back(b.ok ? b.H : 0.0);
    r.H_std.push_back(b.ok ? std::sqrt(b.var / 2.0) : 0.0);  // 0: not usable (fit::MakeBins leaves it out)
    r.coherence.push_back(b.ok ? b.coherence : 0.0);
    r.S_uu.push_back(b.suu);
    r.S_yy.push_back(b.syy);
    r.S_uy.push_back(b.suy);
    out.transient_ratio.push_back(b.transient_ratio);
  }
  r.error_correlation = ErrorCorrelation(bins, W, M);
  double kappa = 1.0;
  for (const cd& c : r.error_correlation) kappa += 2.0 * c.real();
  r.bin_correlation = std::max(1.0, kappa);
  return out;
}

CombinedResponse ToCombined(LocalEstimate estimate, LocalMethod method, int num_runs) {
  CombinedResponse c;
  c.method = method == LocalMethod::kPolynomial ? CombinedMethod::kLpm : CombinedMethod::kLrm;
  c.frf = std::move(estimate.frf);
  c.num_runs = num_runs;
  return c;
}

}  // namespace zwidth::ident
