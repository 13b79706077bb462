// Independent brute force for the Z-width tests (stability_test,
// stability_stress_test): closed-loop roots from companion matrices.
#pragma once

#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "model/plant.h"
#include "model/state_space.h"

namespace zwidth::stability {

// Independent brute force: the closed-loop polynomial from the plant's discrete
// state space, N(z) = det(zI - A + BC) - det(zI - A), and its roots as the
// eigenvalues of the companion matrix.
struct BruteForce {
  Eigen::VectorXd den, num;  // z^0 first
  int d;
  double T;
  static Eigen::VectorXd CharPoly(const Eigen::MatrixXd& M) {
    const Eigen::VectorXcd ev = M.eigenvalues();
    Eigen::VectorXcd c = Eigen::VectorXcd::Zero(ev.size() + 1);
    c(0) = 1.0;
    for (int i = 0; i < ev.size(); ++i) {
      for (int k = i + 1; k > 0; --k) c(k) = c(k - 1) - ev(i) * c(k);
      c(0) = -ev(i) * c(0);
    }
    return c.real();
  }
  BruteForce(const Plant& p, double T_, int d_) : d(d_ + p.delay_samples), T(T_) {
    const StateSpace s = DiscretizeZoh(p, T);
    den = CharPoly(s.A);
    num = CharPoly(s.A - s.B * s.C) - den;
  }
  double MaxRoot(double K, double B) const {
    const int n = static_cast<int>(den.size()) - 1;
    Eigen::VectorXd p = Eigen::VectorXd::Zero(n + d + 2);
    p.segment(d + 1, n + 1) += den;
    for (int i = 0; i < num.size(); ++i) {
      p(i + 1) += (K + B / T) * num(i);
      p(i) += -B / T * num(i);
    }
    int deg = static_cast<int>(p.size()) - 1;
    while (deg > 0 && p(deg) == 0) --deg;
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(deg, deg);
    for (int i = 1; i < deg; ++i) C(i, i - 1) = 1.0;
    for (int i = 0; i < deg; ++i) C(i, deg - 1) = -p(i) / p(deg);
    return C.eigenvalues().cwiseAbs().maxCoeff();
  }
  // Smallest K > 0 with a root on the circle, by a geometric scan and bisection.
  double KCritical(double B, double k_lo = 1e-4, double k_hi = 1e5) const {
    if (MaxRoot(k_lo, B) >= 1.0) return 0.0;
    double prev = k_lo;
    for (double k = k_lo * 1.01; k < k_hi; k *= 1.01) {
      if (MaxRoot(k, B) >= 1.0) {
        double a = prev, b = k;
        for (int i = 0; i < 60; ++i) {
          const double m = 0.5 * (a + b);
          (MaxRoot(m, B) >= 1.0 ? b : a) = m;
        }
        return 0.5 * (a + b);
      }
      prev = k;
    }
    return std::numeric_limits<double>::infinity();
  }
};

}  // namespace zwidth::stability
