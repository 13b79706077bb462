// The numerical kernels the stability module shares (internal, not
// installed): Brent's root and extremum searches, a golden-section search and
// the product of two polynomials. One copy each, used by the Z-width
// (zwidth.cc, zwidth_summary.cc), the haptic loop's sweeps (passivity.cc)
// and the sampled plant (sampled_plant.cc).
#pragma once

#include <cmath>
#include <functional>
#include <vector>

namespace zwidth::stability::internal {

// Brent's method (zeroin) for f(a) f(b) <= 0. A template, so that the
// boundary's B(theta) - B inlines (no std::function call per evaluation).
template <class F>
double BrentRoot(const F& f, double a, double b, double fa, double fb, double tol) {
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  double c = a, fc = fa, d = b - a, e = d;
  for (int iter = 0; iter < 200; ++iter) {
    if ((fb > 0) == (fc > 0)) { c = a; fc = fa; d = e = b - a; }
    if (std::abs(fc) < std::abs(fb)) { a = b; b = c; c = a; fa = fb; fb = fc; fc = fa; }
    const double tol1 = 2.0 * 1e-16 * std::abs(b) + 0.5 * tol;
    const double xm = 0.5 * (c - b);
    if (std::abs(xm) <= tol1 || fb == 0.0) return b;
    if (std::abs(e) >= tol1 && std::abs(fa) > std::abs(fb)) {
      double p, q, r;
      const double s = fb / fa;
      if (a == c) { p = 2.0 * xm * s; q = 1.0 - s; }
      else {
        q = fa / fc; r = fb / fc;
        p = s * (2.0 * xm * q * (q - r) - (b - a) * (r - 1.0));
        q = (q - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0) q = -q;
      p = std::abs(p);
      if (2.0 * p < std::min(3.0 * xm * q - std::abs(tol1 * q), std::abs(e * q))) { e = d; d = p / q; }
      else { d = xm; e = d; }
    } else { d = xm; e = d; }
    a = b; fa = fb;
    b += (std::abs(d) > tol1) ? d : (xm > 0 ? tol1 : -tol1);
    fb = f(b);
  }
  return b;
}

// Golden-section search for the extremum of f on [a, b] (sign = +1 max, -1 min).
double GoldenExtremum(const std::function<double(double)>& f, double a, double b, double sign, double tol);

// Brent's method for the extremum of f on [a, b] (sign = +1 max, -1 min):
// parabolic interpolation through the three best points, a golden-section step
// wherever the parabola does not shrink the bracket (R. P. Brent, Algorithms
// for Minimization without Derivatives, 1973, ch. 5, procedure localmin).
// The same bracket and guarantee as GoldenExtremum, but superlinear on a
// smooth peak: about 10 evaluations where the golden search takes 48 to
// narrow a bracket by 1e-10. It stops once x is within 2 tol of the bracket's
// midpoint and returns the best point evaluated.
template <class F>
double BrentExtremum(const F& f, double a, double b, double sign, double tol) {
  const double golden = 0.5 * (3.0 - std::sqrt(5.0));
  double x = a + golden * (b - a), w = x, v = x, e = 0.0, d = 0.0;
  double fx = -sign * f(x), fw = fx, fv = fx;  // minimised
  for (int iter = 0; iter < 200; ++iter) {
    const double m = 0.5 * (a + b), tol2 = 2.0 * tol;
    if (std::abs(x - m) <= tol2 - 0.5 * (b - a)) break;
    double p = 0.0, q = 0.0, r = 0.0;
    if (std::abs(e) > tol) {  // parabola through x, w, v
      r = (x - w) * (fx - fv);
      q = (x - v) * (fx - fw);
      p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p; else q = -q;
      r = e;
      e = d;
    }
    if (std::abs(p) < std::abs(0.5 * q * r) && p > q * (a - x) && p < q * (b - x)) {
      d = p / q;
      const double u = x + d;
      if (u - a < tol2 || b - u < tol2) d = x < m ? tol : -tol;
    } else {
      e = (x < m ? b : a) - x;
      d = golden * e;
    }
    const double u = x + (std::abs(d) >= tol ? d : (d > 0.0 ? tol : -tol));
    const double fu = -sign * f(u);
    if (fu <= fx) {
      (u < x ? b : a) = x;
      v = w; fv = fw; w = x; fw = fx; x = u; fx = fu;
    } else {
      (u < x ? a : b) = u;
      if (fu <= fw || w == x) { v = w; fv = fw; w = u; fw = fu; }
      else if (fu <= fv || v == x || v == w) { v = u; fv = fu; }
    }
  }
  return x;
}

// The count of closed-loop roots outside the unit circle past a crossing of
// the circle that changes it by `change` (the crossing's direction times its
// weight; `known` false where the direction is lost to rounding): count +
// change, or -1 (not known: the caller counts by the eigenvalues instead)
// where count is not known, the change is not, or the sum leaves [0, order]
// (order: the closed loop's, the most roots there are), which a direction
// of the wrong sign can make it do.
inline int PropagateCount(int count, int change, bool known, int order) {
  if (count < 0 || !known) return -1;
  const int c = count + change;
  return (c >= 0 && c <= order) ? c : -1;
}

// The counts between two directly counted ones: first, then first +
// changes[0], ..., which must reach next (changes[j] == 0: not known). True
// with (*counts)[j] the count after changes[j] (j < changes.size() - 1)
// where every step is known, stays in [0, order] (PropagateCount) and the
// last reaches next; false (counts cleared) else.
inline bool PropagateCounts(int first, int next, const std::vector<int>& changes, int order,
                            std::vector<int>* counts) {
  counts->clear();
  int c = first;
  for (int change : changes) {
    c = PropagateCount(c, change, change != 0, order);
    if (c < 0) { counts->clear(); return false; }
    counts->push_back(c);
  }
  if (c != next) { counts->clear(); return false; }
  if (!counts->empty()) counts->pop_back();  // next's own, counted directly
  return true;
}

// The coefficients of a(z) b(z), lowest power first.
std::vector<double> PolyMul(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace zwidth::stability::internal
