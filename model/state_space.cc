#include "model/state_space.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>

#include "model/error.h"
#include "model/state_space_internal.h"

namespace zwidth::model {

namespace internal {

// Parlett-Reinsch balancing (as LAPACK's dgebal, scaling only): the diagonal
// scales s, powers of two, such that diag(s)^-1 M diag(s) has rows and columns
// of comparable norm.
Eigen::VectorXd BalancingScales(const Eigen::MatrixXd& M) {
  const int n = static_cast<int>(M.rows());
  Eigen::VectorXd s = Eigen::VectorXd::Ones(n);
  Eigen::MatrixXd A = M;
  bool changed = true;
  for (int sweep = 0; changed && sweep < 100; ++sweep) {
    changed = false;
    for (int i = 0; i < n; ++i) {
      double c = 0.0, r = 0.0;
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        c += std::abs(A(j, i));
        r += std::abs(A(i, j));
      }
      if (c == 0.0 || r == 0.0) continue;
      double f = 1.0;
      const double total = c + r;
      while (c < r / 2.0) { c *= 2.0; r /= 2.0; f *= 2.0; }
      while (c >= r * 2.0) { c /= 2.0; r *= 2.0; f /= 2.0; }
      if ((c + r) < 0.95 * total) {
        changed = true;
        s(i) *= f;
        A.row(i) /= f;
        A.col(i) *= f;
      }
    }
  }
  return s;
}

}  // namespace internal

StateSpace ContinuousStateSpace(const Plant& plant) {
  const int n = plant.num_states();
  StateSpace ss;
  ss.A = Eigen::MatrixXd::Zero(n, n);
  ss.B = Eigen::VectorXd::Zero(n);
  ss.C = Eigen::RowVectorXd::Zero(n);
  // Cascade: the output of block k is the input of block k+1, expressed as
  // a row "out" (over states) plus a feedthrough "feed" of the plant input.
  Eigen::RowVectorXd in_row = Eigen::RowVectorXd::Zero(n);  // block input as C x
  double in_feed = 1.0;                                      // ... + in_feed * u
  int k = 0;
  for (const Mode& md : plant.modes) {
    const int p = k, q = k + 1;
    ss.A(p, q) = md.omega;
    ss.A(q, p) = -md.omega;
    ss.A(q, q) = -md.c;
    ss.A.row(q) += in_row;
    ss.B(q) += in_feed;
    const double g = (md.omega * md.omega) / (md.v * md.v);
    Eigen::RowVectorXd out_row = g * in_row;
    out_row(p) += g * (md.v * md.v - md.omega * md.omega) / md.omega;
    out_row(q) += g * (md.d - md.c);
    in_row = out_row;
    in_feed *= g;
    k += 2;
  }
  // Rigid body in momentum-like states (m theta, m theta'), so that 1/m sits
  // in C alone: every entry of A is then of the order of a natural frequency
  // and the matrix exponential keeps its digits (with (theta, theta') the
  // coupling row carries 1/m ~ 1e3 and the ZOH lost ~4 digits on Table I).
  const int th = k, om = k + 1;
  ss.A(th, om) = 1.0;
  ss.A(om, om) = -plant.b / plant.m;
  ss.A.row(om) += in_row;
  ss.B(om) += in_feed;
  ss.C(th) = 1.0 / plant.m;
  ss.D = 0.0;
  return ss;
}

StateSpace DiscretizeZoh(const StateSpace& c, double period_s) {
  if (!std::isfinite(period_s) || period_s <= 0.0) {
    throw InputError("sample period = " + std::to_string(period_s) +
                     " s: must be finite and > 0");
  }
  const int n = static_cast<int>(c.A.rows());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 1, n + 1);
  M.topLeftCorner(n, n) = c.A * period_s;
  M.topRightCorner(n, 1) = c.B * period_s;
  // Balance first (diagonal similarity by powers of two, exact): models whose
  // zeros lie far below their poles carry gains of 1e7 along the cascade, and
  // the exponential of the unbalanced matrix lost up to 5 digits on them.
  const Eigen::VectorXd s = internal::BalancingScales(M);
  const Eigen::MatrixXd Mb = s.cwiseInverse().asDiagonal() * M * s.asDiagonal();
  const Eigen::MatrixXd E = s.asDiagonal() * Mb.exp() * s.cwiseInverse().asDiagonal();
  StateSpace d;
  d.A = E.topLeftCorner(n, n);
  d.B = E.topRightCorner(n, 1);
  d.C = c.C;
  d.D = c.D;
  d.period_s = period_s;
  return d;
}

StateSpace DiscretizeZoh(const Plant& plant, double period_s) {
  StateSpace d = DiscretizeZoh(ContinuousStateSpace(plant), period_s);
  d.delay_samples = plant.delay_samples;
  return d;
}

StateSpace WithDelayStates(const StateSpace& s) {
  const int n = static_cast<int>(s.A.rows());
  const int k = s.delay_samples;
  if (k == 0) return s;
  // States: plant x (n), then the shift register r_1..r_k with r_1 = u_{t-1},
  // r_j = u_{t-j}; the plant is driven by r_k = u_{t-k}.
  StateSpace out;
  out.A = Eigen::MatrixXd::Zero(n + k, n + k);
  out.B = Eigen::VectorXd::Zero(n + k);
  out.C = Eigen::RowVectorXd::Zero(n + k);
  out.A.topLeftCorner(n, n) = s.A;
  out.A.block(0, n + k - 1, n, 1) = s.B;
  for (int j = 1; j < k; ++j) out.A(n + j, n + j - 1) = 1.0;
  out.B(n) = 1.0;
  out.C.head(n) = s.C;
  out.C(n + k - 1) = s.D;  // y_t = C x_t + D u_{t-k}, u_{t-k} = r_k
  out.D = 0.0;  // the input reaches the output through the register only
  out.period_s = s.period_s;
  out.delay_samples = 0;
  return out;
}

DiscreteResponse::DiscreteResponse(const StateSpace& s)
    : D_(s.D), delay_samples_(s.delay_samples) {
  // Balance (exact similarity by powers of two), then reduce to Hessenberg.
  const Eigen::VectorXd sc = internal::BalancingScales(s.A);
  const Eigen::MatrixXd Ab = sc.cwiseInverse().asDiagonal() * s.A * sc.asDiagonal();
  Eigen::HessenbergDecomposition<Eigen::MatrixXd> hd(Ab);
  H_ = hd.matrixH();
  const Eigen::MatrixXd Q = hd.matrixQ();
  QtB_ = Q.transpose() * (sc.cwiseInverse().asDiagonal() * s.B);
  CQ_ = (s.C * sc.asDiagonal()) * Q;
}

std::complex<double> DiscreteResponse::AtZ(std::complex<double> z) const {
  using cd = std::complex<double>;
  const int n = static_cast<int>(H_.rows());
  // Solve (zI - H) x = Q^T B by Gaussian elimination with partial pivoting
  // restricted to the one subdiagonal: O(n^2). The Z-width evaluates this
  // ~1e5 times per model (issue 31: 77 % of a 32-section boundary's time), so:
  // a per-thread row-major buffer instead of an n x n allocation per call;
  // pivots compared by |re| + |im| as LAPACK's izamax does (within sqrt 2 of
  // |.|, no hypot); division by multiplying with conj(d) / |d|^2 (entries of
  // a balanced matrix are far from overflow), not the library's scaled one.
  thread_local std::vector<cd> M;
  thread_local std::vector<cd> x;
  M.resize(static_cast<size_t>(n) * n);
  x.resize(n);
  for (int i = 0; i < n; ++i) {
    cd* row = &M[static_cast<size_t>(i) * n];
    for (int j = std::max(0, i - 1); j < n; ++j) row[j] = -H_(i, j);
    row[i] += z;
    x[i] = QtB_(i);
  }
  auto mag = [](const cd& a) { return std::abs(a.real()) + std::abs(a.imag()); };
  auto inv = [](const cd& a) { return std::conj(a) / std::norm(a); };
  for (int k = 0; k + 1 < n; ++k) {
    cd* rk = &M[static_cast<size_t>(k) * n];
    cd* rk1 = rk + n;
    if (mag(rk1[k]) > mag(rk[k])) {
      for (int j = k; j < n; ++j) std::swap(rk[j], rk1[j]);
      std::swap(x[k], x[k + 1]);
    }
    if (rk1[k] == cd(0.0)) continue;
    const cd l = rk1[k] * inv(rk[k]);
    for (int j = k; j < n; ++j) rk1[j] -= l * rk[j];
    x[k + 1] -= l * x[k];
  }
  cd y = 0.0;
  for (int i = n - 1; i >= 0; --i) {
    const cd* ri = &M[static_cast<size_t>(i) * n];
    cd acc = x[i];
    for (int j = i + 1; j < n; ++j) acc -= ri[j] * x[j];
    x[i] = acc * inv(ri[i]);
    y += CQ_(i) * x[i];
  }
  return y + D_;
}

std::complex<double> DiscreteResponse::AtTheta(double theta) const {
  const std::complex<double> z = std::polar(1.0, theta);
  return AtZ(z) * std::polar(1.0, -theta * delay_samples_);
}

std::vector<double> SimulateDiscrete(const StateSpace& s,
                                     const std::vector<double>& input) {
  const int n = static_cast<int>(s.A.rows());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), next(n);
  std::vector<double> y(input.size());
  const size_t delay = static_cast<size_t>(s.delay_samples);
  for (size_t t = 0; t < input.size(); ++t) {
    const double u_delayed = (t >= delay) ? input[t - delay] : 0.0;
    y[t] = s.C.dot(x) + s.D * u_delayed;
    next.noalias() = s.A * x;
    next += s.B * u_delayed;
    x.swap(next);
  }
  return y;
}

}  // namespace zwidth::model
