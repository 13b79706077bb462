// Independent brute force for the Z-width tests (zwidth_test, closed_loop_test, hand_test,
// zwidth_stress_test): closed-loop roots from companion matrices.
#pragma once

#include <cmath>
#include <algorithm>
#include <functional>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "model/plant.h"
#include "model/state_space.h"
#include "stability/hand.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

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
  BruteForce(const model::Plant& p, double T_, int d_) : d(d_ + p.delay_samples), T(T_) {
    const model::StateSpace s = model::DiscretizeZoh(p, T);
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
  // Smallest K > 0 with a root on the circle (KCriticalOf below).
  double KCritical(double B, double k_lo = 1e-4, double k_hi = 1e5) const;
};

// Smallest K > 0 at which max_root(K, B) reaches 1, by a geometric scan in
// steps of 1 % from k_lo to k_hi and 60 bisections; 0 when unstable at k_lo,
// inf when stable up to k_hi.
template <class MaxRoot>
double KCriticalOf(const MaxRoot& max_root, double B, double k_lo = 1e-4, double k_hi = 1e5) {
  if (max_root(k_lo, B) >= 1.0) return 0.0;
  double prev = k_lo;
  for (double k = k_lo * 1.01; k < k_hi; k *= 1.01) {
    if (max_root(k, B) >= 1.0) {
      double a = prev, b = k;
      for (int i = 0; i < 60; ++i) {
        const double m = 0.5 * (a + b);
        (max_root(m, B) >= 1.0 ? b : a) = m;
      }
      return 0.5 * (a + b);
    }
    prev = k;
  }
  return std::numeric_limits<double>::infinity();
}

inline double BruteForce::KCritical(double B, double k_lo, double k_hi) const {
  return KCriticalOf([this](double K, double b) { return MaxRoot(K, b); }, B, k_lo, k_hi);
}

}  // namespace zwidth::stability

namespace zwidth::stability {

// Independent brute force for the haptic loop (closed_loop_test, hand_test): the closed
// loop as one discrete state-space matrix, its eigenvalues by Eigen.
// States: the sampled plant x (n), the previous output y_{k-1}, the velocity
// filter in transposed direct form II (L states), and the delay line of the
// wall force (D states). Per sample:
//   y = C x,  w = (y - y_prev)/T,  v = b0 w + s_1,  s_i <- b_i w - a_i v + s_{i+1},
//   f = K y + B v,  u = -f delayed D samples,  x <- Ad x + Bd u.
// R: the scalar type. long double (64-bit mantissa) is the referee of the
// Z-width tests where double cannot place a root: with many lightly damped
// modes crowded together the eigenvalues' condition numbers reach ~1e8, and
// double's eigenvalues then err by more than a root's distance to the circle
// 1e-4 (relative, in K) past a crossing (issue 31: 32 sections 1 % apart at
// damping 1e-3 gave |z| = 1 - 4e-10 in double and 1 + 4.3e-8 in long double).
template <typename R>
struct LoopBruteForceT {
  using Mat = Eigen::Matrix<R, Eigen::Dynamic, Eigen::Dynamic>;
  using Vec = Eigen::Matrix<R, Eigen::Dynamic, 1>;
  using Row = Eigen::Matrix<R, 1, Eigen::Dynamic>;
  Mat Ad;
  Vec Bd;
  Row C;
  std::vector<R> b, a;  // filter, padded to the same length L + 1
  int D = 0;
  R T = 0.0;
  // discrete: a sampled plant without input delay; total_delay = loop + plant delay.
  LoopBruteForceT(const Mat& A_, const Vec& B_, const Row& C_, const std::vector<double>& fb,
                  const std::vector<double>& fa, int total_delay, double period)
      : Ad(A_), Bd(B_), C(C_), b(fb.begin(), fb.end()), a(fa.begin(), fa.end()), D(total_delay), T(period) {
    if (b.empty()) { b = {R(1)}; a = {R(1)}; }
    const size_t L1 = std::max(b.size(), a.size());
    b.resize(L1, R(0));
    a.resize(L1, R(0));
  }
  Mat Matrix(double K_, double B_) const {
    const R K = K_, B = B_;
    const int n = static_cast<int>(Ad.rows());
    const int L = static_cast<int>(b.size()) - 1;
    const int N = n + 1 + L + D;
    const int iy = n, is = n + 1, ir = n + 1 + L;
    Row y = Row::Zero(N), w, v, f;
    y.head(n) = C;
    w = y / T;
    w(iy) -= R(1) / T;
    v = b[0] * w;
    if (L > 0) v(is) += R(1);
    f = K * y + B * v;
    Row u = D == 0 ? Row(-f) : Row(Row::Zero(N));
    if (D > 0) u(ir + D - 1) = R(-1);
    Mat M = Mat::Zero(N, N);
    M.topLeftCorner(n, n) = Ad;
    M.topRows(n) += Bd * u;
    M.row(iy) = y;
    for (int i = 1; i <= L; ++i) {
      M.row(is + i - 1) = b[i] * w - a[i] * v;
      if (i < L) M(is + i - 1, is + i) += R(1);
    }
    if (D > 0) {
      M.row(ir) = f;
      for (int i = 1; i < D; ++i) M(ir + i, ir + i - 1) = R(1);
    }
    return M;
  }
  double MaxRoot(double K, double B) const {
    return static_cast<double>(Matrix(K, B).eigenvalues().cwiseAbs().maxCoeff());
  }
};
using LoopBruteForce = LoopBruteForceT<double>;

// e^M by scaling and squaring of a Taylor series, for the scalars Eigen's
// matrix exponential does not know (tests/brute_force_wide.h): M halved
// until its infinity norm is below 1/64, 20 terms (truncation below
// (1/64)^21 / 21! = 1e-58 relative), squared back.
template <typename Mat>
Mat TaylorExp(const Mat& M) {
  using R = typename Mat::Scalar;
  R norm = 0;
  for (int i = 0; i < M.rows(); ++i) {
    R row = 0;
    for (int j = 0; j < M.cols(); ++j) row += abs(M(i, j));
    if (row > norm) norm = row;
  }
  int squarings = 0;
  Mat X = M;
  while (norm > R(1) / R(64)) { norm /= R(2); X /= R(2); ++squarings; }
  Mat E = Mat::Identity(M.rows(), M.cols()), term = E;
  for (int k = 1; k <= 20; ++k) { term = (term * X) / R(k); E += term; }
  for (int i = 0; i < squarings; ++i) E = E * E;
  return E;
}

// The plant of eq. (1) realised the other way round from model/state_space.cc
// (u -> rigid body (theta, theta') -> section 1 -> ... -> y; section (x1, x2):
// x1' = -c x1 - w x2 + in, x2' = w x1, out = g ((d - c) x1 + (v^2 - w^2)/w x2 + in),
// g = w^2 / v^2, so that (sI - A)^-1 e1 = (s, w) / (s^2 + c s + w^2) and
// out / in = g (s^2 + d s + v^2) / (s^2 + c s + w^2)), sampled by Eigen's
// matrix exponential without balancing (TaylorExp for other scalars), in the
// scalar R (double; long double for a referee with 3 more digits; 30
// decimal digits in tests/brute_force_wide.h): the discrete A, B, C.
template <typename R>
struct IndependentZoh {
  using Mat = typename LoopBruteForceT<R>::Mat;
  using Vec = typename LoopBruteForceT<R>::Vec;
  using Row = typename LoopBruteForceT<R>::Row;
  Mat A;
  Vec B;
  Row C;
  IndependentZoh(const model::Plant& p, double T_) {
    const R T = T_, m = p.m, b = p.b;
    const int n = 2 + 2 * static_cast<int>(p.modes.size());
    Mat Ac = Mat::Zero(n, n);
    Vec Bc = Vec::Zero(n);
    Ac(0, 1) = R(1);
    Ac(1, 1) = -b / m;
    Bc(1) = R(1) / m;
    Row out = Row::Zero(n);
    out(0) = R(1);
    for (size_t k = 0; k < p.modes.size(); ++k) {
      const R w = p.modes[k].omega, c = p.modes[k].c, v = p.modes[k].v, d = p.modes[k].d;
      const int i = 2 + 2 * static_cast<int>(k);
      Ac(i, i) = -c;
      Ac(i, i + 1) = -w;
      Ac(i + 1, i) = w;
      Ac.row(i) += out;
      const R g = w * w / (v * v);
      Row next = g * out;
      next(i) += g * (d - c);
      next(i + 1) += g * (v * v - w * w) / w;
      out = next;
    }
    Mat M = Mat::Zero(n + 1, n + 1);
    M.topLeftCorner(n, n) = Ac * T;
    M.topRightCorner(n, 1) = Bc * T;
    Mat E;
    if constexpr (std::is_floating_point_v<R>) E = M.exp();
    else E = TaylorExp(M);  // Eigen's exp knows float, double and long double only
    A = E.topLeftCorner(n, n);
    B = E.topRightCorner(n, 1);
    C = out;
  }
};

// The loop brute force of a plant (with the loop's hand): its own ZOH,
// e^{[[A, B], [0, 0]] T} without balancing; well conditioned for heavy
// devices, where BruteForce's N(z) = det(zI - A + BC) - det(zI - A) loses its
// digits to cancellation.
inline LoopBruteForce MakeBrute(const model::Plant& p, const LoopOptions& loop, int delay, double T) {
  const model::StateSpace c = ContinuousStateSpaceWithHand(p, loop.hand);
  const int n = static_cast<int>(c.A.rows());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 1, n + 1);
  M.topLeftCorner(n, n) = c.A * T;
  M.topRightCorner(n, 1) = c.B * T;
  const Eigen::MatrixXd E = M.exp();
  return LoopBruteForce(E.topLeftCorner(n, n), E.topRightCorner(n, 1), c.C, loop.filter_b, loop.filter_a,
                        delay + p.delay_samples, T);
}

// Points of a (K, B) grid classified by ZWidth::StableIntervals and by a brute
// force's largest closed-loop root (stable when < 1).
struct Tally {
  long points = 0, stable = 0, reopened = 0, near_boundary = 0, disagree = 0;
  long refereed = 0;  // points the referee decided (max_root disagreed)
};

// The grid: num_b values of B from 0 to b_top; at each, K on a geometric scan
// of min_points / num_b + 1 values from 2e-4 to 2 k_top (k_top: the largest
// finite interval end or crossing), points_inside values inside each stable
// interval, and points 1e-4 (relative) inside and outside each finite end. A
// disagreement counts only when the brute force's verdict is the same at
// K (1 +- 1e-6) and B (1 +- 1e-6), i.e. outside a relative 1e-6 neighbourhood
// of a boundary; each one is a test failure, and the classification stops
// after the sixth.
struct ClassifyGrid {
  double b_top = 0.0;
  int num_b = 0;
  int min_points = 0;
  int points_inside = 0;
};

// referee, when given: the same brute force more precisely (long double),
// which decides every point where max_root disagrees with the Z-width, and
// the neighbourhood test there.
inline Tally Classify(const ZWidth& z, const std::function<double(double, double)>& max_root, const model::Plant& p,
                      double T, int delay, const ClassifyGrid& g,
                      const std::function<double(double, double)>& referee = {}) {
  Tally t;
  auto stable_bf = [&](double K, double B) { return max_root(K, B) < 1.0; };
  for (int i = 0; i < g.num_b; ++i) {
    const double B = g.b_top * i / (g.num_b - 1);
    const std::vector<KInterval> iv = z.StableIntervals(B);
    double k_top = 0.0;
    for (const KInterval& v : iv) k_top = std::max(k_top, std::isfinite(v.K_hi) ? v.K_hi : v.K_lo);
    for (const Crossing& x : z.Crossings(B)) if (x.K > 0 && std::isfinite(x.K)) k_top = std::max(k_top, x.K);
    if (!(k_top > 0.0)) k_top = 100.0 * p.m / (T * T);
    std::vector<double> ks;
    const int nk = g.min_points / g.num_b + 1;
    for (int j = 0; j < nk; ++j) ks.push_back(k_top * 2.0 * std::pow(1e-4, 1.0 - double(j) / (nk - 1)));
    for (const KInterval& v : iv) {
      const double lo = v.K_lo > 0 ? v.K_lo : 1e-3 * v.K_hi, hi = std::isfinite(v.K_hi) ? v.K_hi : 10 * lo;
      for (int j = 1; j <= g.points_inside; ++j) ks.push_back(lo * std::pow(hi / lo, j / (g.points_inside + 1.0)));
    }
    for (const KInterval& v : iv) {
      if (v.K_lo > 0) { ks.push_back(v.K_lo * (1 + 1e-4)); ks.push_back(v.K_lo * (1 - 1e-4)); }
      if (std::isfinite(v.K_hi)) { ks.push_back(v.K_hi * (1 - 1e-4)); ks.push_back(v.K_hi * (1 + 1e-4)); }
    }
    for (double K : ks) {
      bool mine = false, reopened = false;
      for (const KInterval& v : iv) {
        if (K > v.K_lo && K < v.K_hi) { mine = true; reopened = v.K_lo > 0.0; }
      }
      bool ref = stable_bf(K, B);
      ++t.points;
      t.stable += mine;
      t.reopened += mine && reopened;
      if (mine != ref && referee) { ref = referee(K, B) < 1.0; ++t.refereed; }
      if (mine == ref) continue;
      auto side = [&](double k, double b) { return referee ? referee(k, b) < 1.0 : stable_bf(k, b); };
      const bool flips = side(K * (1 + 1e-6), B) != ref || side(K * (1 - 1e-6), B) != ref ||
                         side(K, B * (1 + 1e-6)) != ref || side(K, B * (1 - 1e-6)) != ref;
      if (flips) { ++t.near_boundary; continue; }
      ++t.disagree;
      ADD_FAILURE() << "d=" << delay << " B=" << B << " K=" << K << " intervals say " << mine
                    << ", eigenvalues (max |z| " << (referee ? referee(K, B) : max_root(K, B)) << ") say " << ref;
      if (t.disagree > 5) return t;
    }
  }
  return t;
}

}  // namespace zwidth::stability
