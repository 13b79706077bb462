// The linear rational start (Sanathanan & Koerner 1963), factored into eq. (1).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fit/fit_internal.h"
#include "model/plant.h"

namespace zwidth::fit::internal {

// Roots of the real polynomial sum_i a[i] x^i (a.back() != 0), from the
// eigenvalues of its companion matrix.
std::vector<cd> Roots(const std::vector<double>& a) {
  const int deg = static_cast<int>(a.size()) - 1;
  if (deg < 1) return {};
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(deg, deg);
  for (int i = 1; i < deg; ++i) C(i, i - 1) = 1.0;
  for (int i = 0; i < deg; ++i) C(i, deg - 1) = -a[i] / a[deg];
  Eigen::EigenSolver<Eigen::MatrixXd> es(C, false);
  std::vector<cd> r(deg);
  for (int i = 0; i < deg; ++i) r[i] = es.eigenvalues()[i];
  return r;
}

// Second-order factors (s^2 + 2 zeta w s + w^2) from roots: complex pairs
// directly, the real roots paired in order (an overdamped factor).
std::vector<std::pair<double, double>> Quadratics(std::vector<cd> r) {
  std::vector<std::pair<double, double>> q;  // (w, 2 zeta w)
  std::vector<double> real;
  for (const cd& x : r) {
    if (std::abs(x.imag()) > 1e-9 * std::abs(x)) {
      if (x.imag() > 0) q.push_back({std::abs(x), -2.0 * x.real()});
    } else {
      real.push_back(x.real());
    }
  }
  std::sort(real.begin(), real.end());
  for (size_t i = 0; i + 1 < real.size(); i += 2) {
    q.push_back({std::sqrt(std::abs(real[i] * real[i + 1])), -(real[i] + real[i + 1])});
  }
  return q;
}

namespace {

// The Sanathanan-Koerner passes on F(sigma) = N(sigma) / D'(sigma) with the
// per-bin weights wt: each pass solves N - F (a_0 + ... + a_{dd-1}
// sigma^{dd-1}) = F sigma^dd in least squares, weighted by wt / |D'_prev|.
// false when a solution is not finite.
bool SkPasses(const std::vector<cd>& F, const std::vector<cd>& sig, const std::vector<double>& wt, int n,
              int iterations, std::vector<double>* num, std::vector<double>* den) {
  const size_t nb = F.size();
  const int dd = 2 * n + 1, unknowns = dd + 2 * n + 1;
  std::vector<double> den_prev(dd + 1, 0.0);
  den_prev[0] = 1.0;  // first pass: D'_prev = 1
  bool first = true;
  num->assign(2 * n + 1, 0.0);
  den->assign(dd + 1, 0.0);
  Eigen::MatrixXd A(2 * nb, unknowns);
  Eigen::VectorXd rhs(2 * nb);
  for (int it = 0; it < iterations; ++it) {
    for (size_t k = 0; k < nb; ++k) {
      cd dp = 1.0;
      if (!first) {
        dp = 0.0;
        for (int i = dd; i >= 0; --i) dp = dp * sig[k] + den_prev[i];
      }
      const double w = wt[k] / std::max(std::abs(dp), 1e-300);
      cd p = 1.0;
      // N(sigma) - F (a_0 + ... + a_{dd-1} sigma^{dd-1}) = F sigma^dd
      for (int i = 0; i <= 2 * n; ++i) {
        A(2 * k, i) = w * p.real();
        A(2 * k + 1, i) = w * p.imag();
        p *= sig[k];
      }
      p = 1.0;
      for (int i = 0; i < dd; ++i) {
        const cd c = -F[k] * p * w;
        A(2 * k, 2 * n + 1 + i) = c.real();
        A(2 * k + 1, 2 * n + 1 + i) = c.imag();
        p *= sig[k];
      }
      const cd r = F[k] * p * w;  // p = sigma^dd
      rhs(2 * k) = r.real();
      rhs(2 * k + 1) = r.imag();
    }
    Eigen::VectorXd colscale = A.colwise().norm();
    for (int j = 0; j < unknowns; ++j) if (!(colscale(j) > 0)) colscale(j) = 1.0;
    const Eigen::MatrixXd As = A * colscale.cwiseInverse().asDiagonal();
    const Eigen::VectorXd sol = As.colPivHouseholderQr().solve(rhs).cwiseQuotient(colscale);
    if (!sol.allFinite()) return false;
    for (int i = 0; i <= 2 * n; ++i) (*num)[i] = sol(i);
    for (int i = 0; i < dd; ++i) (*den)[i] = sol(2 * n + 1 + i);
    (*den)[dd] = 1.0;
    den_prev = *den;
    first = false;
  }
  return true;
}

// The rational fit's roots (in sigma = s / w0) as eq. (1) with m = 1: the
// real pole nearest 0 is the rigid pole -b/m, the rest pair into sections.
std::optional<model::Plant> ModalShape(const std::vector<double>& num, const std::vector<double>& den, int n, double w0) {
  // Poles: the real root nearest 0 is the rigid pole -b/m; the rest pair up.
  std::vector<cd> poles = Roots(den), zeros = Roots(num);
  if (num[2 * n] == 0.0 || poles.empty()) return std::nullopt;
  size_t ia = poles.size();
  for (size_t i = 0; i < poles.size(); ++i) {
    if (std::abs(poles[i].imag()) > 1e-9 * std::abs(poles[i])) continue;
    if (ia == poles.size() || std::abs(poles[i]) < std::abs(poles[ia])) ia = i;
  }
  if (ia == poles.size()) return std::nullopt;
  const double a = -poles[ia].real() * w0;
  poles.erase(poles.begin() + ia);
  auto qp = Quadratics(poles), qz = Quadratics(zeros);
  if (static_cast<int>(qp.size()) != n || static_cast<int>(qz.size()) != n) return std::nullopt;
  model::Plant p;
  p.m = 1.0;
  p.b = std::max(std::abs(a), 1e-3);
  for (int i = 0; i < n; ++i) {
    p.modes.push_back({qp[i].first * w0, std::max(std::abs(qp[i].second), 1e-6) * w0, qz[i].first * w0,
                       std::max(std::abs(qz[i].second), 1e-6) * w0});
  }
  CanonicalOrder(&p, nullptr);
  return p;
}

}  // namespace

std::optional<model::Plant> LinearRationalStart(const ident::FrequencyResponse& frf, int n, int delay, int iterations) {
  const size_t nb = frf.f_hz.size();
  const int dd = 2 * n + 1;  // D'(s) monic of degree 2n + 1, N(s) of degree 2n
  const int unknowns = dd + 2 * n + 1;
  if (n < 1 || static_cast<int>(2 * nb) <= unknowns + 4) return std::nullopt;
  const double T = frf.period_s();
  const double w0 = kTwoPi * frf.f_hz.back();
  auto weight = [&](size_t k) {  // 1 / (w s_k): F = s H below has std w s_k
    const double s = std::max(frf.H_std[k], 1e-3 * std::abs(frf.H[k]));
    return (s > 0 && std::isfinite(s)) ? 1.0 / (kTwoPi * frf.f_hz[k] * s) : 0.0;
  };
  // F = s H with the delay and the ZOH's half sample taken out: a strictly
  // proper rational N / D' in sigma = s / w0.
  std::vector<cd> F(nb), sig(nb);
  std::vector<double> wt(nb);
  for (size_t k = 0; k < nb; ++k) {
    const double w = kTwoPi * frf.f_hz[k];
    sig[k] = cd(0.0, w / w0);
    F[k] = cd(0.0, w) * frf.H[k] * std::polar(1.0, w * T * (delay + 0.5));
    wt[k] = weight(k);
  }
  std::vector<double> num, den;
  if (!SkPasses(F, sig, wt, n, iterations, &num, &den)) return std::nullopt;
  std::optional<model::Plant> shape = ModalShape(num, den, n, w0);
  if (!shape) return std::nullopt;
  model::Plant p = *shape;
  // 1 / m by weighted least squares on H = G_1 / m (G_1: this shape with m = 1).
  double num_m = 0, den_m = 0;
  for (size_t k = 0; k < nb; ++k) {
    const double w = kTwoPi * frf.f_hz[k];
    const cd g1 = model::ContinuousResponse(p, w) * std::polar(1.0, -w * T * (delay + 0.5));
    const double q = weight(k) * w;
    num_m += q * q * (std::conj(g1) * frf.H[k]).real();
    den_m += q * q * std::norm(g1);
  }
  const double inv_m = num_m / den_m;
  if (!(inv_m > 0) || !std::isfinite(inv_m)) return std::nullopt;
  p.m = 1.0 / inv_m;
  p.b *= p.m;
  std::string why;
  if (!p.IsValid(&why)) return std::nullopt;
  return p;
}

}  // namespace zwidth::fit::internal
