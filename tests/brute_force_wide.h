// The brute force of tests/brute_force.h in 30 decimal digits: the referee
// where long double cannot place the critical root (zwidth_wide_referee_test,
// bench/zwidth_benchmark.cc). Boost.Multiprecision's cpp_bin_float (header
// only; Eigen's eigensolver runs on it through boost/multiprecision/eigen.hpp);
// where Boost is missing ZWIDTH_HAVE_WIDE_BRUTE_FORCE is 0 and nothing is
// defined.
//
// Why: with 32 lightly damped sections 1 % apart (damping ratio 1e-4) the
// critical root moves by only 4e-5 in |z| per unit of ln K, while long
// double's eigenvalues of the unbalanced realisation err by ~2e-11 in |z|
// (measured: at K_CR(0) (1 - 1e-9) long double gives |z| = 1 - 2.1e-11, 30
// and 50 digits and binary128 give 1 - 4.0e-14): a bisection of the long
// double brute force then misplaces K_CR(0) by 1.6e-6 where the 30-digit,
// 50-digit and binary128 ones agree with each other to 1e-14 and with the
// Z-width to 3e-12.
#pragma once

#if __has_include(<boost/multiprecision/cpp_bin_float.hpp>) && __has_include(<boost/multiprecision/eigen.hpp>)
#define ZWIDTH_HAVE_WIDE_BRUTE_FORCE 1
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/eigen.hpp>

#include <Eigen/Eigenvalues>

#include "tests/brute_force.h"

namespace zwidth::stability {

using Wide = boost::multiprecision::number<boost::multiprecision::cpp_bin_float<30>, boost::multiprecision::et_off>;

// The loop brute force of IndependentZoh<Wide> (its own realisation and a
// Taylor ZOH, tests/brute_force.h) with the loop's delay, no filter.
struct WideBruteForce {
  LoopBruteForceT<Wide> loop;
  WideBruteForce(const model::Plant& p, int delay, double T)
      : WideBruteForce(IndependentZoh<Wide>(p, T), delay + p.delay_samples, T) {}
  // The largest |eigenvalue| - 1 (so that a root 1e-14 off the circle stays
  // visible in double).
  double MaxRootMinusOne(double K, double B) const {
    Eigen::EigenSolver<LoopBruteForceT<Wide>::Mat> es(loop.Matrix(K, B), false);
    Wide m = 0;
    for (int i = 0; i < es.eigenvalues().size(); ++i) {
      const Wide a = abs(es.eigenvalues()(i));
      if (a > m) m = a;
    }
    return static_cast<double>(m - Wide(1));
  }

 private:
  WideBruteForce(const IndependentZoh<Wide>& z, int total_delay, double T)
      : loop(z.A, z.B, z.C, {}, {}, total_delay, T) {}
};

// The boundary near k: bisection of WideBruteForce on [lo, hi] = k (1 -+
// span) for `steps` steps; nan when the two ends do not straddle it.
inline double WideBisect(const WideBruteForce& bf, double k, double B, double span, int steps) {
  double lo = k * (1 - span), hi = k * (1 + span);
  const bool s_lo = bf.MaxRootMinusOne(lo, B) < 0, s_hi = bf.MaxRootMinusOne(hi, B) < 0;
  if (s_lo == s_hi) return std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < steps; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((bf.MaxRootMinusOne(mid, B) < 0) == s_lo ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace zwidth::stability
#else
#define ZWIDTH_HAVE_WIDE_BRUTE_FORCE 0
#endif
