// The closed loop of eq. (2) as one discrete state matrix, and the stability
// test every Z-width caller uses (ZWidth::IsStable).
//
// Why a state matrix and not the characteristic polynomial: the polynomial's
// coefficients in the monomial basis determine its roots badly when many
// lightly damped poles crowd together (issue 31: 8 sections 8 % apart at
// damping ratio 0.025 put roots of modulus 0.9985 at 1.04 after rounding the
// coefficients to double; Schur-Cohn then called a stable loop unstable). The
// eigenvalues of a matrix built from the balanced ZOH state space (entries of
// the order of the natural frequencies times T, model/state_space.h) are
// backward stable: they are the exact eigenvalues of a matrix within ~n eps
// of it, and for non-defective lightly damped modes that moves them by about
// that much. The polynomial (Schur-Cohn, O(n^2)) is kept only where its root
// conditioning is proven good enough (PolynomialConditioning below).
//
// States, per sample k (as the devices run the loop):
//   x      the sampled plant (n), position state p = the rigid body's
//   e      y_k - y_{k-1}, the backward difference (instead of y_{k-1}),
//   s      the velocity filter in transposed direct form II (L states),
//   r      the delay line of the wall force, r_j = f_{k-j} (D states),
// with y = C x, w = e / T, v = b0 w + s_1, s_i <- b_i w - a_i v + s_{i+1},
// f = K y + B v, u = -r_D (-f when D = 0), x <- A x + Bd u,
// e <- C (A - I) x + C Bd u.
// Written with e rather than y_{k-1}, the position state's column is e_p at
// K = 0 when the plant has its integrator (nothing but the position depends
// on the position: C (A - I) e_p = 0), so the integrator's eigenvalue at 1
// deflates exactly: K -> 0+ is decided on the other states.
#pragma once

#include <complex>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "model/state_space.h"

namespace zwidth::stability {

class ClosedLoopMatrix {
 public:
  // discrete: the sampled plant without delay; position_state: the index of
  // the integrator's state (its column of A is e_p), -1 when the plant has no
  // integrator; filter_b/filter_a over powers of z^-1 (both empty: F = 1);
  // total_delay: loop delay + the model's own, in samples.
  ClosedLoopMatrix(const model::StateSpace& discrete, int position_state, std::vector<double> filter_b,
                   std::vector<double> filter_a, int total_delay, double period_s);

  // The matrix at (K, B); with deflate, the position's row and column
  // removed (valid at K = 0 only, where they hold the eigenvalue 1 alone).
  Eigen::MatrixXd Matrix(double K, double B, bool deflate) const;
  // Largest |eigenvalue| of the balanced matrix.
  double SpectralRadius(double K, double B, bool deflate) const;
  // How many eigenvalues have |z| >= 1.
  int RootsOutside(double K, double B, bool deflate) const;
  int order() const { return n_ + 1 + L_ + D_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd Bd_;
  Eigen::RowVectorXd C_;
  std::vector<double> b_, a_;
  int n_ = 0, L_ = 0, D_ = 0, position_ = -1;
  double T_ = 0.0;
};

// How far the roots of a real polynomial move when its coefficients are
// rounded: for each root r_i, eps sum_k |p_k| |r_i|^k / |p'(r_i)| (Wilkinson's
// first-order bound for relative coefficient errors of eps), the largest over
// the roots. Roots given exactly (the discrete poles e^{pT}); z^0 first.
double RootDisplacementBound(const std::vector<double>& coeffs, const std::vector<std::complex<double>>& roots);

}  // namespace zwidth::stability
