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

std::vector<cd> Dft(const double* v, int n) { return ForwardReal(std::vector<double>(v, v + n)); }

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

// One bin's least squares, min |a - K theta| over the rows (run i, bin j)
// with K = [A | B]: A the complex columns (x_j r^s wt_j, s = 0..R; the LRM's
// -a_j r^s, s = 1..R_D), B the transient's real columns wt_j r^s, one block
// per run, the same W x (R + 1) block in every run. It is solved as the
// full problem would be, without factoring it (Frisch-Waugh-Lovell): with
// Q_B an orthonormal basis of B's block (real, made once per bin and shared
// by the runs and the channels) and P = I - Q_B Q_B^T on each run's rows,
// theta_A minimises |P a - P A theta_A| (a complex QR of p_A = R + 1 (+ R_D)
// columns instead of p_A + M (R + 1)), the residual is P a - P A theta_A,
// the hat matrix's diagonal is |Q_B(j)|^2 + |(P A R_A^-1)(j)|^2, and the
// transient's coefficients are R_B^-1 Q_B^T (a - A theta_A). Columns are
// scaled to unit norm first (A over all rows, B over one run's).
//
// The buffers of one thread, sized once: every bin's problem has the same
// shape, so nothing is allocated per bin.
struct Workspace {
  Workspace(int runs, int window, int a_cols, int b_cols, int channels)
      : M(runs), W(window), m(runs * window), pa(a_cols), pb(b_cols), A(static_cast<size_t>(m) * a_cols),
        QR(A.size()), PA(A.size()), a(m), qa(m), proj_a(m), ca(static_cast<size_t>(runs) * b_cols), cA(ca.size() * a_cols),
        tau(a_cols), theta(a_cols), h(a_cols), x(a_cols), q(a_cols), norm(a_cols), inv_diag(a_cols),
        QB(static_cast<size_t>(window) * b_cols), RB(static_cast<size_t>(b_cols) * b_cols), norm_b(b_cols),
        leverage_b(window), c(channels, std::vector<cd>(m)), e(channels, std::vector<cd>(m)) {}
  int M, W, m, pa, pb;
  std::vector<cd> A;   // the scaled complex columns, column-major (A[col * m + row])
  std::vector<cd> QR;  // P A's Householder QR: R on and above the diagonal, the reflectors below
  std::vector<cd> PA;  // P A
  std::vector<cd> a, qa, proj_a;  // a, then Q^H P a; P a
  std::vector<cd> ca, cA;  // Q_B^T a and Q_B^T A_col per run (ca[i * pb + s], cA[(col * M + i) * pb + s])
  std::vector<cd> tau, theta, h, x, q;
  std::vector<double> norm, inv_diag;
  std::vector<double> QB, RB, norm_b, leverage_b;  // Q_B (column-major), R_B (column-major), B's norms, |Q_B(j)|^2
  bool b_ok = false;
  std::vector<std::vector<cd>> c, e;  // per channel: the row coefficients c_j and the residuals
};

// One channel's local least squares at one bin (the row coefficients and
// residuals left in ws.c[channel], ws.e[channel]).
struct ChannelFit {
  cd g = 0.0;                  // G' at the bin (of the differenced output)
  double transient_ratio = 0.0;
  double q_eff = 0.0;          // the residual's degrees of freedom in units of sigma^2
  bool ok = false;
};

// The geometry shared by every channel of one bin.
struct LocalWindow {
  int k = 0, start = 0, W = 0, q = 0, np = 0;  // bin, first bin, bins, residual dof, DFT length
  const double* row_weight = nullptr;  // of the window's bins: 1 / |1 - e^{-j theta_j}|^d
};

// Q_B and R_B of the transient's block wt_j (r_j / n)^s, columns scaled to
// unit norm, by modified Gram-Schmidt applied twice ("twice is enough":
// orthogonal to rounding for the small, moderately conditioned blocks here).
void FactorTransientBlock(const LocalWindow& w, const LocalModelOptions& o, Workspace& ws) {
  const int W = ws.W, t = ws.pb, n = o.HalfWidth();
  std::fill(ws.RB.begin(), ws.RB.end(), 0.0);
  for (int jj = 0; jj < W; ++jj) {
    const double rr = static_cast<double>(w.start + jj - w.k) / n;
    double pw = w.row_weight[jj];
    for (int s = 0; s < t; ++s, pw *= rr) ws.QB[s * W + jj] = pw;
  }
  ws.b_ok = false;
  for (int s = 0; s < t; ++s) {
    double* q = &ws.QB[s * W];
    double ss = 0.0;
    for (int jj = 0; jj < W; ++jj) ss += q[jj] * q[jj];
    ws.norm_b[s] = std::sqrt(ss);
    if (!(ws.norm_b[s] > 0.0) || !std::isfinite(ws.norm_b[s])) return;
    for (int jj = 0; jj < W; ++jj) q[jj] /= ws.norm_b[s];
    for (int pass = 0; pass < 2; ++pass) {
      for (int l = 0; l < s; ++l) {
        const double* ql = &ws.QB[l * W];
        double dot = 0.0;
        for (int jj = 0; jj < W; ++jj) dot += ql[jj] * q[jj];
        for (int jj = 0; jj < W; ++jj) q[jj] -= dot * ql[jj];
        ws.RB[s * t + l] += dot;
      }
    }
    double nn = 0.0;
    for (int jj = 0; jj < W; ++jj) nn += q[jj] * q[jj];
    nn = std::sqrt(nn);
    if (!(nn > 1e-10)) return;  // B's columns (unit norm) dependent
    for (int jj = 0; jj < W; ++jj) q[jj] /= nn;
    ws.RB[s * t + s] = nn;
  }
  for (int jj = 0; jj < W; ++jj) {
    double l = 0.0;
    for (int s = 0; s < t; ++s) l += ws.QB[s * W + jj] * ws.QB[s * W + jj];
    ws.leverage_b[jj] = l;
  }
  ws.b_ok = true;
}

// y <- P y on every run's rows; the coefficients Q_B^T y of run i to coef[i * pb + s].
void ProjectOutTransient(Workspace& ws, cd* y, cd* coef) {
  for (int i = 0; i < ws.M; ++i) {
    cd* yi = y + i * ws.W;
    for (int s = 0; s < ws.pb; ++s) {
      const double* q = &ws.QB[s * ws.W];
      cd dot = 0.0;
      for (int jj = 0; jj < ws.W; ++jj) dot += q[jj] * yi[jj];
      coef[i * ws.pb + s] = dot;
    }
    for (int s = 0; s < ws.pb; ++s) {
      const double* q = &ws.QB[s * ws.W];
      const cd dot = coef[i * ws.pb + s];
      for (int jj = 0; jj < ws.W; ++jj) yi[jj] -= dot * q[jj];
    }
  }
}

// Householder QR of the m x pa matrix ws.QR in place (LAPACK zgeqr2's
// convention: H_c = I - tau_c v_c v_c^H with v_c(c) = 1 and R's diagonal
// real), applying H_c^H to ws.qa as it goes (ws.qa = Q^H qa).
void HouseholderQr(Workspace& ws) {
  const int m = ws.m, p = ws.pa;
  for (int c = 0; c < p; ++c) {
    cd* v = &ws.QR[static_cast<size_t>(c) * m];
    const cd alpha = v[c];
    double tail = 0.0;
    for (int i = c + 1; i < m; ++i) tail += std::norm(v[i]);
    cd tau = 0.0;
    double beta = alpha.real();
    if (tail > std::numeric_limits<double>::min() || alpha.imag() != 0.0) {
      beta = std::sqrt(std::norm(alpha) + tail);
      if (alpha.real() >= 0.0) beta = -beta;
      const cd inv = 1.0 / (alpha - beta);
      for (int i = c + 1; i < m; ++i) v[i] *= inv;
      tau = (beta - alpha) / beta;
    } else {
      for (int i = c + 1; i < m; ++i) v[i] = 0.0;
    }
    v[c] = beta;
    ws.tau[c] = tau;
    auto reflect = [&](cd* y) {  // y <- (I - conj(tau) v v^H) y
      cd t = y[c];
      for (int i = c + 1; i < m; ++i) t += std::conj(v[i]) * y[i];
      t *= std::conj(tau);
      y[c] -= t;
      for (int i = c + 1; i < m; ++i) y[i] -= t * v[i];
    };
    for (int c2 = c + 1; c2 < p; ++c2) reflect(&ws.QR[static_cast<size_t>(c2) * m]);
    reflect(ws.qa.data());
  }
}

ChannelFit SolveChannel(const std::vector<RunDft>& runs, int channel, const LocalWindow& w, const LocalModelOptions& o,
                        Workspace& ws) {
  const int M = ws.M, W = ws.W, R = o.order, n = o.HalfWidth();
  const bool rational = o.method == LocalMethod::kRational;
  const int rows = ws.m, p = ws.pa, t = ws.pb;
  auto A = [&](int row, int col) -> cd& { return ws.A[static_cast<size_t>(col) * rows + row]; };
  auto Rm = [&](int row, int col) { return ws.QR[static_cast<size_t>(col) * rows + row]; };
  ChannelFit f;
  if (!ws.b_ok) return f;
  for (int i = 0; i < M; ++i) {
    for (int jj = 0; jj < W; ++jj) {
      const int j = w.start + jj, row = i * W + jj;
      const double rr = static_cast<double>(j - w.k) / n, wt = w.row_weight[jj];
      ws.a[row] = runs[i].z[channel][j] * wt;
      double pw = 1.0;
      for (int s = 0; s <= R; ++s, pw *= rr) A(row, s) = runs[i].x[j] * (wt * pw);
      if (rational) {
        pw = rr;
        for (int s = 1; s <= o.denominator_order; ++s, pw *= rr) A(row, R + s) = -ws.a[row] * pw;
      }
    }
  }
  for (int c = 0; c < p; ++c) {
    double ss = 0.0;
    for (int row = 0; row < rows; ++row) ss += std::norm(A(row, c));
    ws.norm[c] = std::sqrt(ss);
    if (!(ws.norm[c] > 0.0) || !std::isfinite(ws.norm[c])) return f;
    for (int row = 0; row < rows; ++row) A(row, c) /= ws.norm[c];
  }
  std::copy(ws.A.begin(), ws.A.end(), ws.QR.begin());
  std::copy(ws.a.begin(), ws.a.end(), ws.qa.begin());
  for (int c = 0; c < p; ++c) ProjectOutTransient(ws, &ws.QR[static_cast<size_t>(c) * rows], &ws.cA[static_cast<size_t>(c) * M * t]);
  ProjectOutTransient(ws, ws.qa.data(), ws.ca.data());
  std::copy(ws.qa.begin(), ws.qa.end(), ws.proj_a.begin());  // P a and P A, kept for the residual
  std::copy(ws.QR.begin(), ws.QR.end(), ws.PA.begin());
  HouseholderQr(ws);
  // Rank: the diagonal of R_A (P A's columns; |.| <= 1) and of R_B (1 first)
  // against the largest, as a QR of the whole [A | B] would test it.
  double dmin = std::abs(Rm(0, 0)), dmax = std::max(dmin, 1.0);
  for (int c = 1; c < p; ++c) dmin = std::min(dmin, std::abs(Rm(c, c)));
  for (int s = 0; s < t; ++s) dmin = std::min(dmin, ws.RB[s * t + s]);
  if (!(dmin > 1e-10 * dmax)) return f;
  for (int c = 0; c < p; ++c) ws.inv_diag[c] = 1.0 / Rm(c, c).real();  // R's diagonal is real
  // theta_A = R^-1 (Q^H P a)_{0..p-1}; h = R^-H e_0 and x = R^-1 h, so that
  // (P A) x is the row combination that gives theta_0: theta_0 = ((P A) x)^H a.
  for (int i = p - 1; i >= 0; --i) {
    cd s = ws.qa[i];
    for (int j = i + 1; j < p; ++j) s -= Rm(i, j) * ws.theta[j];
    ws.theta[i] = s * ws.inv_diag[i];
    if (!std::isfinite(ws.theta[i].real()) || !std::isfinite(ws.theta[i].imag())) return f;
  }
  for (int i = 0; i < p; ++i) {
    cd s = i == 0 ? 1.0 : 0.0;
    for (int j = 0; j < i; ++j) s -= std::conj(Rm(j, i)) * ws.h[j];
    ws.h[i] = s * ws.inv_diag[i];
  }
  for (int i = p - 1; i >= 0; --i) {
    cd s = ws.h[i];
    for (int j = i + 1; j < p; ++j) s -= Rm(i, j) * ws.x[j];
    ws.x[i] = s * ws.inv_diag[i];
  }
  std::vector<cd>& e = ws.e[channel];
  std::vector<cd>& coef = ws.c[channel];
  // For the LPM (D = 1) q_eff = trace(I - P) = rows - all unknowns.
  f.q_eff = rational ? 0.0 : static_cast<double>(rows - p - M * t);
  for (int row = 0; row < rows; ++row) {
    cd fit = 0.0, qh = 0.0;
    for (int c = 0; c < p; ++c) {
      const cd pa = ws.PA[static_cast<size_t>(c) * rows + row];
      fit += pa * ws.theta[c];
      qh += pa * ws.x[c];
    }
    e[row] = ws.proj_a[row] - fit;
    // Row j's error is D(r_j) V_j (the LRM's equations are multiplied by D; D
    // = 1 for the LPM): G' - G = sum_j c_j D(r_j) V_j, and the residual's
    // expected square is sigma^2 sum_j (1 - P_jj) |D(r_j)|^2 (P_jj the hat
    // matrix's diagonal, `leverage`), which makes the degrees of freedom q_eff.
    cd D = 1.0;
    if (rational) {
      const double rr = static_cast<double>(w.start + row % W - w.k) / n;
      double pw = rr;
      for (int s = 1; s <= o.denominator_order; ++s, pw *= rr) D += ws.theta[R + s] / ws.norm[R + s] * pw;
      // row `row` of (P A) R^-1: q R = (P A)(row, .)
      double leverage = ws.leverage_b[row % W];
      for (int c = 0; c < p; ++c) {
        cd s = ws.PA[static_cast<size_t>(c) * rows + row];
        for (int l = 0; l < c; ++l) s -= ws.q[l] * Rm(l, c);
        ws.q[c] = s * ws.inv_diag[c];
        leverage += std::norm(ws.q[c]);
      }
      f.q_eff += std::max(0.0, 1.0 - leverage) * std::norm(D);
    }
    coef[row] = std::conj(qh) / ws.norm[0] * D;
  }
  f.g = ws.theta[0] / ws.norm[0];
  // The transient at the bin (r = 0) of run i: t_0 = (R_B^-1 Q_B^T (a - A theta_A))_0 / |B_0|.
  for (int i = 0; i < M; ++i) {
    for (int s = t - 1; s >= 0; --s) {
      cd v = ws.ca[i * t + s];
      for (int c = 0; c < p; ++c) v -= ws.cA[(static_cast<size_t>(c) * M + i) * t + s] * ws.theta[c];
      for (int l = s + 1; l < t; ++l) v -= ws.RB[l * t + s] * ws.q[l];
      ws.q[s] = v / ws.RB[s * t + s];
    }
    const cd t0 = ws.q[0] / ws.norm_b[0];
    const double resp = std::abs(f.g * runs[i].x[w.k]);
    f.transient_ratio = std::max(f.transient_ratio, resp > 0 ? std::abs(t0) / resp : 0.0);
  }
  f.ok = true;
  return f;
}

// The estimate at one bin: G, its error as a linear functional of the
// channels' row noise (alpha[channel * rows + row], in a store owned by the
// caller) and the channels' noise covariance Sigma.
struct BinEstimate {
  cd H = 0.0;
  double var = 0.0, coherence = 0.0, transient_ratio = 0.0;
  double suu = 0.0, syy = 0.0;
  cd suy = 0.0;
  const cd* alpha = nullptr;
  Eigen::Matrix2cd sigma = Eigen::Matrix2cd::Zero();
  Eigen::Matrix2cd gram = Eigen::Matrix2cd::Zero();  // sum_j alpha_c(j) conj(alpha_c'(j))
  int start = 0, channels = 0, rows = 0;
  bool ok = false;
};

// sum_{c,c'} Sigma_cc' sum_j a_c(j) conj(b_c'(j)) over the rows the windows share
// (b's window starts `shift` bins later).
cd Covariance(const BinEstimate& a, const BinEstimate& b, const Eigen::Matrix2cd& sigma, int W, int M) {
  const int shift = b.start - a.start;
  cd s = 0.0;
  for (int c = 0; c < a.channels; ++c) {
    for (int c2 = 0; c2 < b.channels; ++c2) {
      cd t = 0.0;
      for (int i = 0; i < M; ++i) {
        for (int jj = std::max(0, shift); jj < W && jj - shift < W; ++jj) {
          t += a.alpha[c * a.rows + i * W + jj] * std::conj(b.alpha[c2 * b.rows + i * W + jj - shift]);
        }
      }
      s += sigma(c, c2) * t;
    }
  }
  return s;
}

// Covariance(b, b, sigma) from b's Gram matrix.
cd SelfCovariance(const BinEstimate& b, const Eigen::Matrix2cd& sigma) {
  cd s = 0.0;
  for (int c = 0; c < b.channels; ++c) {
    for (int c2 = 0; c2 < b.channels; ++c2) s += sigma(c, c2) * b.gram(c, c2);
  }
  return s;
}

BinEstimate EstimateBin(const std::vector<RunDft>& runs, const LocalWindow& w, double psd_scale,
                        const LocalModelOptions& o, Workspace& ws, cd* alpha) {
  const int M = static_cast<int>(runs.size()), channels = static_cast<int>(runs[0].z.size()), rows = ws.m;
  BinEstimate b;
  b.start = w.start;
  b.channels = channels;
  b.rows = rows;
  b.alpha = alpha;
  ChannelFit f[2];
  FactorTransientBlock(w, o, ws);
  for (int c = 0; c < channels; ++c) {
    f[c] = SolveChannel(runs, c, w, o, ws);
    if (!f[c].ok || !(f[c].q_eff > 0.0)) return b;
  }
  for (int c = 0; c < channels; ++c) {
    for (int c2 = 0; c2 < channels; ++c2) {
      cd s = 0.0;
      for (int r = 0; r < rows; ++r) s += ws.e[c][r] * std::conj(ws.e[c2][r]);
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
  const cd one_minus = 1.0 - std::exp(cd(0.0, -theta));
  cd D = 1.0;
  for (int i = 0; i < o.differences; ++i) D *= one_minus;
  if (channels == 1) {
    const cd inv_d = 1.0 / D;
    b.H = f[0].g * inv_d;
    for (int r = 0; r < rows; ++r) alpha[r] = ws.c[0][r] * inv_d;
    b.transient_ratio = f[0].transient_ratio;
  } else {  // closed loop: G = G'_ry / G'_ru (the differences cancel)
    const cd inv_g = 1.0 / f[0].g, minus_h_inv_g = -(f[1].g * inv_g) * inv_g;
    b.H = f[1].g * inv_g;
    for (int r = 0; r < rows; ++r) alpha[r] = ws.c[0][r] * minus_h_inv_g;
    for (int r = 0; r < rows; ++r) alpha[rows + r] = ws.c[1][r] * inv_g;
    b.transient_ratio = f[1].transient_ratio;
  }
  for (int c = 0; c < channels; ++c) {
    for (int c2 = 0; c2 < channels; ++c2) {
      cd t = 0.0;
      for (int r = 0; r < rows; ++r) t += alpha[c * rows + r] * std::conj(alpha[c2 * rows + r]);
      b.gram(c, c2) = t;
    }
  }
  b.var = std::max(0.0, SelfCovariance(b, b.sigma).real());
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
  std::vector<cd> sum(L, 0.0);
  std::vector<int> count(L, 0);
  for (size_t k = 0; k < bins.size(); ++k) {
    const BinEstimate& a = bins[k];
    if (!a.ok) continue;
    for (int l = 1; l <= L && k + l < bins.size(); ++l) {
      const BinEstimate& b = bins[k + l];
      if (!b.ok || b.start - a.start >= W) continue;
      const double va = a.var, vb = SelfCovariance(b, a.sigma).real();
      if (!(va > 0.0 && vb > 0.0)) continue;
      sum[l - 1] += Covariance(a, b, a.sigma, W, M) / std::sqrt(va * vb);
      ++count[l - 1];
    }
  }
  std::vector<cd> rho(L, 0.0);
  for (int l = 0; l < L; ++l) rho[l] = count[l] > 0 ? sum[l] / static_cast<double>(count[l]) : 0.0;
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
  // The row weights 1 / |1 - e^{-j theta_j}|^d of every bin a window may hold.
  std::vector<double> row_weight(kmax + 1, 0.0);
  for (int j = 1; j <= kmax; ++j) {
    const double th = 2.0 * std::numbers::pi * j / np;
    row_weight[j] = 1.0 / std::pow(std::abs(1.0 - std::exp(cd(0.0, -th))), d);
  }
  const int channels = static_cast<int>(dft[0].z.size()), rows = M * W;
  const int a_cols = o.order + 1 + (o.method == LocalMethod::kRational ? o.denominator_order : 0);
  std::vector<cd> alpha(ks.size() * channels * rows);
  std::vector<BinEstimate> bins(ks.size());
  const size_t chunk = 256;
  ParallelFor((ks.size() + chunk - 1) / chunk, [&](size_t c) {
    Workspace ws(M, W, a_cols, o.order + 1, channels);
    LocalWindow w;
    w.W = W;
    w.q = out.residual_dof;
    w.np = np;
    for (size_t i = c * chunk; i < std::min(ks.size(), (c + 1) * chunk); ++i) {
      w.k = ks[i];
      w.start = std::clamp(w.k - hw, 1, kmax - W + 1);
      w.row_weight = &row_weight[w.start];
      bins[i] = EstimateBin(dft, w, 2.0 / (fs * np), o, ws, &alpha[i * channels * rows]);
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
