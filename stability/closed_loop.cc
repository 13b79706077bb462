#include "stability/closed_loop.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Eigenvalues>

#include "model/error.h"
#include "model/state_space_internal.h"

namespace zwidth::stability {

ClosedLoopMatrix::ClosedLoopMatrix(const model::StateSpace& s, int position_state, std::vector<double> fb,
                                   std::vector<double> fa, int total_delay, double period_s)
    : A_(s.A), Bd_(s.B), C_(s.C), b_(std::move(fb)), a_(std::move(fa)), D_(total_delay), position_(position_state),
      T_(period_s) {
  if (b_.empty()) { b_ = {1.0}; a_ = {1.0}; }
  const size_t L1 = std::max(b_.size(), a_.size());
  b_.resize(L1, 0.0);
  a_.resize(L1, 0.0);
  n_ = static_cast<int>(A_.rows());
  L_ = static_cast<int>(L1) - 1;
}

Eigen::MatrixXd ClosedLoopMatrix::Matrix(double K, double B, bool deflate) const {
  const int n = n_, L = L_, D = D_, N = order();
  const int ie = n, is = n + 1, ir = n + 1 + L;
  Eigen::RowVectorXd y = Eigen::RowVectorXd::Zero(N);
  y.head(n) = C_;
  Eigen::RowVectorXd w = Eigen::RowVectorXd::Zero(N);
  w(ie) = 1.0 / T_;
  Eigen::RowVectorXd v = b_[0] * w;
  if (L > 0) v(is) += 1.0;
  const Eigen::RowVectorXd f = K * y + B * v;
  Eigen::RowVectorXd u = Eigen::RowVectorXd::Zero(N);
  if (D == 0) u = -f;
  else u(ir + D - 1) = -1.0;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(N, N);
  M.topLeftCorner(n, n) = A_;
  M.topRows(n) += Bd_ * u;
  M.row(ie) = C_.dot(Bd_) * u;
  M.block(ie, 0, 1, n) += C_ * A_ - C_;
  for (int i = 1; i <= L; ++i) {
    M.row(is + i - 1) = b_[i] * w - a_[i] * v;
    if (i < L) M(is + i - 1, is + i) += 1.0;
  }
  if (D > 0) {
    M.row(ir) = f;
    for (int i = 1; i < D; ++i) M(ir + i, ir + i - 1) = 1.0;
  }
  if (!deflate || position_ < 0) return M;
  // Drop the position's row and column: at K = 0 its column is e_p up to the
  // rounding of the ZOH (C (A - I) e_p = 0), so the rest keeps every other eigenvalue.
  Eigen::MatrixXd R(N - 1, N - 1);
  const int p = position_, q = N - 1 - p;
  R.topLeftCorner(p, p) = M.topLeftCorner(p, p);
  R.topRightCorner(p, q) = M.topRightCorner(p, q);
  R.bottomLeftCorner(q, p) = M.bottomLeftCorner(q, p);
  R.bottomRightCorner(q, q) = M.bottomRightCorner(q, q);
  return R;
}

namespace {

Eigen::VectorXcd Eigenvalues(const Eigen::MatrixXd& M) {
  // Balance (exact similarity by powers of two): K and B / T scale rows by up
  // to 1e6 against the plant's entries of order 1.
  const Eigen::VectorXd sc = model::internal::BalancingScales(M);
  const Eigen::MatrixXd Mb = sc.cwiseInverse().asDiagonal() * M * sc.asDiagonal();
  Eigen::EigenSolver<Eigen::MatrixXd> es(Mb, false);
  if (es.info() != Eigen::Success) {
    throw ComputationError("the closed loop's eigenvalues did not converge (order " + std::to_string(M.rows()) + ")");
  }
  return es.eigenvalues();
}

}  // namespace

int ClosedLoopMatrix::RootsOutside(double K, double B, bool deflate) const {
  const Eigen::VectorXcd ev = Eigenvalues(Matrix(K, B, deflate));
  int n = 0;
  for (int i = 0; i < ev.size(); ++i) n += !(std::abs(ev(i)) < 1.0);
  return n;
}

double ClosedLoopMatrix::SpectralRadius(double K, double B, bool deflate) const {
  return Eigenvalues(Matrix(K, B, deflate)).cwiseAbs().maxCoeff();
}

double RootDisplacementBound(const std::vector<double>& p, const std::vector<std::complex<double>>& roots) {
  double worst = 0.0;
  for (const std::complex<double>& r : roots) {
    std::complex<double> dp = 0.0, val = 0.0;
    double mag = 0.0, rk = 1.0;
    for (size_t k = p.size(); k-- > 0;) {
      dp = dp * r + val;
      val = val * r + p[k];
    }
    for (double c : p) { mag += std::abs(c) * rk; rk *= std::abs(r); }
    const double bound = 2.220446049250313e-16 * mag / std::abs(dp);
    worst = std::max(worst, std::isfinite(bound) ? bound : std::numeric_limits<double>::infinity());
  }
  return worst;
}

}  // namespace zwidth::stability
