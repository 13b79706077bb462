// The covariance of a weighted least-squares fit to a Welch frequency response
// whose errors are correlated between neighbouring bins (internal to fit/).
//
// The model-based covariance s2 kappa (J^T J)^-1 (chi2/dof s2 times the
// window's bin correlation kappa = sum_l |rho_X(l)|^2) holds when every bin's
// error is the noise through the window: then neighbouring H errors correlate
// by |rho_X(l)|^2 and a parameter that moves many neighbouring bins together
// sees its variance grow by kappa (1.94 for Hann). At low frequencies the error
// of H1 is mostly leakage of the rigid body's steep spectrum (the segment's
// transient over U): smooth over frequency, so neighbouring H errors correlate
// by rho_X(l) itself (-2/3 at lag 1 for Hann), and kappa overstates the
// variance of m and b, which those bins set (measured on Table I logs: the
// std of m and b 1.45x their scatter over 40 repeated logs, the modes' 0.9x).
// The covariance below keeps the bins' variance of the weighted least squares
// (chi2/dof, the weights trusted) but measures the correlation between bins k
// and k + l (l <= L) from the fit's own residuals e, locally: rho_k(l) = sum
// e_j . e_{j+l} / sum |e_j|^2 over the 49 bins around k, so that leakage-
// dominated and noise-dominated bands each get theirs:
//   C = s2 A^-1 M A^-1,  A = J^T J,
//   M = A + sum_{k, l = 1..L} rho_k(l) (J_k^T J_{k+l} + J_{k+l}^T J_k),
// J_k the two rows (real, imaginary) of bin k, k + l by position in the
// frequency response. L = 2 for Hann and Hamming (w^2 holds cosines of up to
// two cycles, so bins three apart are uncorrelated). Where M is not positive
// definite no correlation is assumed (M = A).
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace zwidth::fit::internal {

// Bins either side of a bin over which the correlation of its residuals is measured.
constexpr long kHalfWindow = 24;

// J: 2 N x p weighted Jacobian (rows 2k, 2k + 1 the real and imaginary parts of
// bin k), r: the 2 N weighted residuals, position: each bin's index in the
// frequency response (ascending), A_inv = (J^T J)^-1. Precondition: sizes agree.
inline Eigen::MatrixXd BinCorrelatedCovariance(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                               const std::vector<long>& position, const Eigen::MatrixXd& A_inv,
                                               int max_lag) {
  const long nb = static_cast<long>(position.size());
  const long p = J.cols();
  const double s2 = r.squaredNorm() / std::max(1.0, static_cast<double>(r.size() - p));  // chi2/dof
  // Prefix sums over bins of |e_k|^2 and, per lag l, of e_k . e_k' for the pair
  // (k, k') with position[k'] - position[k] = l (0 where there is none).
  std::vector<double> e2(nb + 1, 0.0);
  for (long k = 0; k < nb; ++k) e2[k + 1] = e2[k] + r.segment(2 * k, 2).squaredNorm();
  std::vector<std::vector<double>> c(max_lag + 1, std::vector<double>(nb + 1, 0.0));
  std::vector<std::vector<long>> partner(max_lag + 1, std::vector<long>(nb, -1));
  for (int l = 1; l <= max_lag; ++l) {
    for (long k = 0; k < nb; ++k) {
      double v = 0.0;
      for (long j = k + 1; j < nb && position[j] - position[k] <= l; ++j) {
        if (position[j] - position[k] == l) {
          partner[l][k] = j;
          v = r.segment(2 * k, 2).dot(r.segment(2 * j, 2));
        }
      }
      c[l][k + 1] = c[l][k] + v;
    }
  }
  Eigen::MatrixXd M = J.transpose() * J;  // lag 0: A
  for (int l = 1; l <= max_lag; ++l) {
    for (long k = 0; k < nb; ++k) {
      const long j = partner[l][k];
      if (j < 0) continue;
      const long a = std::max(0L, k - kHalfWindow), b = std::min(nb, k + kHalfWindow + 1);
      const double den = e2[b] - e2[a];
      if (!(den > 0.0)) continue;  // residuals exactly zero around k: no correlation measured
      const double rho = std::clamp((c[l][b] - c[l][a]) / den, -1.0, 1.0);
      const Eigen::MatrixXd x = rho * J.middleRows(2 * k, 2).transpose() * J.middleRows(2 * j, 2);
      M += x + x.transpose();
    }
  }
  if (!M.allFinite() ||
      !(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() >= 0.0)) {
    M = J.transpose() * J;  // the measured correlations do not make a covariance: none assumed
  }
  return s2 * A_inv * M * A_inv;
}

// The same sandwich with the correlation the estimator reports
// (ident::FrequencyResponse::error_correlation, rho_l complex for lags l =
// 1..L, as the local methods compute it from their overlapping windows):
// between the (real, imaginary) rows of bins k and k + l the correlation is
// [[Re rho, -Im rho], [Im rho, Re rho]] for circular errors, so
//   M = A + sum_{k, l} (J_k^T P_l J_{k+l} + its transpose).
// Where M is not positive definite no correlation is assumed (M = A).
inline Eigen::MatrixXd KnownCorrelationCovariance(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                                  const std::vector<long>& position, const Eigen::MatrixXd& A_inv,
                                                  const std::vector<std::complex<double>>& rho) {
  const long nb = static_cast<long>(position.size()), L = static_cast<long>(rho.size());
  const double s2 = r.squaredNorm() / std::max(1.0, static_cast<double>(r.size() - J.cols()));
  Eigen::MatrixXd M = J.transpose() * J;
  for (long k = 0; k < nb; ++k) {
    for (long j = k + 1; j < nb && position[j] - position[k] <= L; ++j) {
      const std::complex<double> c = rho[position[j] - position[k] - 1];
      Eigen::Matrix2d P;
      P << c.real(), -c.imag(), c.imag(), c.real();
      const Eigen::MatrixXd x = J.middleRows(2 * k, 2).transpose() * P * J.middleRows(2 * j, 2);
      M += x + x.transpose();
    }
  }
  if (!M.allFinite() ||
      !(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() >= 0.0)) {
    M = J.transpose() * J;
  }
  return s2 * A_inv * M * A_inv;
}

}  // namespace zwidth::fit::internal
