#include "stability/zwidth.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <numbers>
#include <stdexcept>

#include "model/cancel.h"
#include "model/error.h"
#include "stability/closed_loop.h"
#include "stability/haptic_loop.h"
#include "stability/schur_cohn.h"
#include <Eigen/Eigenvalues>

namespace zwidth::stability {
namespace internal {

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
double GoldenExtremum(const std::function<double(double)>& f, double a, double b, double sign,
                      double tol) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = sign * f(x1), f2 = sign * f(x2);
  while (b - a > tol) {
    if (f1 > f2) { b = x2; x2 = x1; f2 = f1; x1 = b - g * (b - a); f1 = sign * f(x1); }
    else { a = x1; x1 = x2; f1 = f2; x2 = a + g * (b - a); f2 = sign * f(x2); }
  }
  return 0.5 * (a + b);
}

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

std::vector<double> PolyMul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> r(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

}  // namespace internal

using internal::BrentRoot;
using internal::PolyMul;

bool BoundaryOptions::IsValid(std::string* why) const {
  auto bad = [&](const char* m) { if (why) *why = std::string("BoundaryOptions::") + m; return false; };
  if (min_grid_points < 64) return bad("min_grid_points must be >= 64");
  if (grid_points_per_delay < 8) return bad("grid_points_per_delay must be >= 8");
  if (!(theta_tolerance > 0.0 && theta_tolerance < 1e-3)) return bad("theta_tolerance must be in (0, 1e-3)");
  return true;
}

bool CriticalPoint::AgreesWithMargin(double rel_tol) const {
  if (std::isnan(K_margin)) return K_cr == 0.0 || std::isinf(K_cr);
  return std::abs(K_margin - K_cr) <= rel_tol * std::max(std::abs(K_cr), 1e-300);
}

namespace {

// The checks of the one-loop constructors, in their historical order (plant,
// delay, loop, then the period in the discretisation).
SampledPlant SampleForOneLoop(const model::Plant& plant, double period_s, int delay_samples, const LoopOptions& loop) {
  plant.Validate();
  if (delay_samples < 0) {
    throw InputError("delay = " + std::to_string(delay_samples) + " samples: must be >= 0");
  }
  if (delay_samples > 100000) throw InputError("delay is over 100000 samples");
  std::string why;
  if (!loop.IsValid(&why)) throw InputError("loop options: " + why);
  return SampledPlant(plant, period_s, loop.hand);
}

bool SameHand(const Hand& a, const Hand& b) { return a.M == b.M && a.B == b.B && a.K == b.K; }

}  // namespace

ZWidth::ZWidth(const model::Plant& plant, double period_s, int delay_samples,
               const BoundaryOptions& options)
    : ZWidth(plant, period_s, delay_samples, LoopOptions{}, options) {}

ZWidth::ZWidth(const model::Plant& plant, double period_s, int delay_samples, const LoopOptions& loop,
               const BoundaryOptions& options)
    : ZWidth(SampleForOneLoop(plant, period_s, delay_samples, loop), delay_samples, loop, options) {}

ZWidth::ZWidth(const SampledPlant& sampled, int delay_samples, const LoopOptions& loop,
               const BoundaryOptions& options)
    : sp_(sampled),
      period_s_(sampled.period_s()),
      total_delay_(delay_samples + sampled.plant().delay_samples),
      loop_(loop),
      options_(options) {
  if (!SameHand(loop.hand, sampled.hand())) {
    throw std::invalid_argument("ZWidth: loop.hand differs from the hand the plant was sampled with");
  }
  if (delay_samples < 0) {
    throw InputError("delay = " + std::to_string(delay_samples) + " samples: must be >= 0");
  }
  if (delay_samples > 100000) throw InputError("delay is over 100000 samples");
  std::string why;
  if (!loop.IsValid(&why)) throw InputError("loop options: " + why);
  if (!options_.IsValid(&why)) throw InputError("boundary options: " + why);
  has_integrator_ = sp_.has_integrator();
  has_filter_ = loop_.HasFilter();
  if (has_filter_) {
    // b_i z^-i and a_i z^-i times z^L: coefficient of z^{L - i}.
    const size_t L = std::max(loop_.filter_b.size(), loop_.filter_a.size()) - 1;
    fn_.assign(L + 1, 0.0);
    fd_.assign(L + 1, 0.0);
    for (size_t i = 0; i < loop_.filter_b.size(); ++i) fn_[L - i] = loop_.filter_b[i];
    for (size_t i = 0; i < loop_.filter_a.size(); ++i) fd_[L - i] = loop_.filter_a[i];
  }
  closed_loop_ = std::make_shared<const ClosedLoopMatrix>(sp_.discrete(), sp_.position_state(), loop_.filter_b,
                                                          loop_.filter_a, total_delay_, period_s_);
  BuildGrid();
  ChooseStabilityTest();
  const std::complex<double> gpi = sp_.gd_at_minus_one();
  const double sgn = (total_delay_ % 2 == 0) ? 1.0 : -1.0;  // z^d at z = -1
  K_pi_at_zero_B_ = (-sgn / gpi).real();
  V_pi_ = V(-1.0, 0.0).real();
  // dW/dx and dV/dx at x = -1 (real axis), by central differences at two
  // steps; kept only where the two agree to 1e-4 (else a theta = pi crossing
  // has no known direction and is probed).
  auto W_at = [&](double x) { return (-std::pow(x, total_delay_) / sp_.Gd({x, 0.0})).real(); };
  auto V_at = [&](double x) {
    std::complex<double> F = 1.0;
    if (has_filter_) {
      std::complex<double> nb = 0.0, na = 0.0;
      for (size_t i = loop_.filter_b.size(); i-- > 0;) nb = nb / x + loop_.filter_b[i];
      for (size_t i = loop_.filter_a.size(); i-- > 0;) na = na / x + loop_.filter_a[i];
      F = nb / na;
    }
    return (F * (1.0 - 1.0 / x) / period_s_).real();
  };
  auto slope = [](const auto& f) {
    const double h1 = 1e-4, h2 = 2.5e-5;
    const double d1 = (f(-1.0 + h1) - f(-1.0 - h1)) / (2 * h1), d2 = (f(-1.0 + h2) - f(-1.0 - h2)) / (2 * h2);
    return std::isfinite(d2) && std::abs(d1 - d2) <= 1e-4 * std::abs(d2) ? d2 : std::numeric_limits<double>::quiet_NaN();
  };
  dW_pi_ = slope(W_at);
  dV_pi_ = slope(V_at);
  zero_k_b_ = ZeroKCandidates();
  zero_k_counts_ = std::make_shared<std::vector<std::atomic<int>>>(zero_k_b_.size() + 1);
  for (std::atomic<int>& c : *zero_k_counts_) c.store(-1);
}

void ZWidth::BuildGrid() {
  // theta grid: uniform, plus the sampled plant's dense patches around every
  // resonance and antiresonance (width ~ damping * T), so that sharp modes are
  // resolved.
  const int n = static_cast<int>(sp_.denominator().size()) - 1;
  const int nu = std::max(options_.min_grid_points,
                          options_.grid_points_per_delay * (total_delay_ + n + static_cast<int>(fd_.size())));
  const std::vector<double>& patches = sp_.mode_patch_theta();
  std::vector<double> th;
  th.reserve(nu + 1 + patches.size());
  const double pi = std::numbers::pi;
  th.push_back(pi * 1e-7);
  for (int i = 1; i < nu; ++i) th.push_back(pi * i / nu);
  th.push_back(pi * (1.0 - 1e-9));
  th.insert(th.end(), patches.begin(), patches.end());
  std::sort(th.begin(), th.end());
  th.erase(std::unique(th.begin(), th.end()), th.end());
  grid_theta_ = th;
  grid_B_.resize(th.size());
  grid_K_.resize(th.size());
  for (size_t i = 0; i < th.size(); ++i) Point(th[i], &grid_B_[i], &grid_K_[i]);

  // Monotone pieces of B(theta) between refined extrema.
  auto Bof = [this](double t) { double b, k; Point(t, &b, &k); return b; };
  std::vector<double> breaks = {th.front()};
  for (size_t i = 1; i + 1 < th.size(); ++i) {
    const double d1 = grid_B_[i] - grid_B_[i - 1], d2 = grid_B_[i + 1] - grid_B_[i];
    if (d1 * d2 < 0.0) {
      const double sign = d1 > 0 ? 1.0 : -1.0;
      // The peak's position to sqrt(eps) of its cell (Brent's own tolerance):
      // B is flat there to ~eps relative, so the pieces' end values B(break)
      // are exact to rounding and no root is lost beside them.
      breaks.push_back(internal::BrentExtremum(Bof, th[i - 1], th[i + 1], sign,
                                               1.5e-8 * (th[i + 1] - th[i - 1]) + 1e-15));
    }
  }
  breaks.push_back(th.back());
  for (size_t i = 0; i + 1 < breaks.size(); ++i) {
    if (!(breaks[i + 1] > breaks[i])) continue;
    Segment sg{breaks[i], breaks[i + 1], Bof(breaks[i]), Bof(breaks[i + 1]), 0, -1};
    sg.ia = static_cast<int>(std::upper_bound(th.begin(), th.end(), sg.ta) - th.begin());
    sg.ib = static_cast<int>(std::lower_bound(th.begin(), th.end(), sg.tb) - th.begin()) - 1;
    segments_.push_back(sg);
  }
}

std::complex<double> ZWidth::V(double c, double s) const {
  const std::complex<double> zi(c, -s);  // z^-1 on the circle
  std::complex<double> F = 1.0;
  if (has_filter_) {
    std::complex<double> nb = 0.0, na = 0.0;
    for (size_t i = loop_.filter_b.size(); i-- > 0;) nb = nb * zi + loop_.filter_b[i];
    for (size_t i = loop_.filter_a.size(); i-- > 0;) na = na * zi + loop_.filter_a[i];
    F = nb / na;
  }
  return F * (1.0 - zi) / period_s_;
}

void ZWidth::Point(double theta, double* B, double* K) const {
  const double c = std::cos(theta), s = std::sin(theta);
  const std::complex<double> z(c, s);
  // z^d by repeated squaring (one sincos instead of two; error ~ d eps).
  std::complex<double> zd = 1.0, zp = z;
  for (int e = total_delay_; e > 0; e >>= 1) {
    if (e & 1) zd *= zp;
    zp *= zp;
  }
  const std::complex<double> W = -zd / sp_.Gd(z);
  if (has_filter_) {
    const std::complex<double> v = V(c, s);
    *B = W.imag() / v.imag();
    *K = W.real() - *B * v.real();
    return;
  }
  *B = period_s_ * W.imag() / s;
  *K = W.real() - W.imag() * (s / (1.0 + c));  // tan(theta / 2)
}

void ZWidth::ChooseStabilityTest() {
  // Schur-Cohn reads the polynomial's coefficients, and rounding them moves
  // its roots. Two checks that it cannot misplace a root across the circle:
  // D(z)'s exactly known poles (K -> 0+) move by under 1e-3 of their distance
  // to the circle, and on the D-decomposition curve, where e^{j theta} is an
  // exact root at (K(theta), B(theta)), the rounding moves the boundary by a
  // relative dK/K or dB/B of at most kPolynomialRelativeTolerance:
  // eps sum |p_k| / |dP/dK K| (or / |dP/dB B|), since dz = -dP / P'(z).
  // The same bound, looser, decides whether Schur-Cohn may verify the ends
  // (Verify): those points lie 1e-6 (relative) off a boundary, which rounding
  // the coefficients cannot move past them while it moves it by at most
  // kPolynomialVerifyTolerance, a hundredth of that.
  polynomial_error_ = 0.0;
  const bool poles_ok = sp_.denominator_pole_shift() <= 1e-3;
  for (size_t i = 0; poles_ok && i < grid_theta_.size(); ++i) {
    const double K = grid_K_[i], B = grid_B_[i];
    if (!(std::isfinite(K) && std::isfinite(B) && K >= 0.0 && B >= 0.0)) continue;
    const std::vector<double> p = CharacteristicPolynomial(K, B);
    const std::complex<double> z = std::polar(1.0, grid_theta_[i]);
    double mag = 0.0;
    for (double c : p) mag += std::abs(c);
    std::complex<double> n = 0.0, fd = 0.0, fn = 0.0;
    for (size_t k = sp_.numerator().size(); k-- > 0;) n = n * z + sp_.numerator()[k];
    for (size_t k = fd_.size(); k-- > 0;) fd = fd * z + fd_[k];
    for (size_t k = fn_.size(); k-- > 0;) fn = fn * z + fn_[k];
    const double dp = std::max(std::abs(K * z * fd * n), std::abs(B / period_s_ * (z - 1.0) * fn * n));
    const double e = 2.220446049250313e-16 * mag / dp;
    polynomial_error_ = std::max(polynomial_error_, std::isfinite(e) ? e : 1.0);
    if (polynomial_error_ > kPolynomialVerifyTolerance) break;
  }
  use_polynomial_ = poles_ok && polynomial_error_ <= kPolynomialRelativeTolerance;
  polynomial_verifies_ = poles_ok && polynomial_error_ <= kPolynomialVerifyTolerance;
}

std::string ConditioningWarning(bool polynomial_test, const PoleConditioning& c) {
  if (polynomial_test || !(c.eigenvalue_shift > kEigenvalueShiftWarning)) return "";
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "ill-conditioned poles: rounding can move a pole of the sampled plant by %.3g of its distance to "
                "the unit circle (eigenvalue condition %.3g, relative pole separation %.3g); (K, B) within about "
                "that (relative) of a boundary may be misclassified",
                c.eigenvalue_shift, c.eigenvalue_condition, c.relative_separation);
  return buf;
}

std::string StabilityTestNote(const DelaySummary& s) {
  if (s.polynomial_test) return "";
  char buf[300];
  if (!(s.pole_shift <= 1e-3)) {
    std::snprintf(buf, sizeof buf,
                  "stability from the closed loop's eigenvalues: rounding the characteristic polynomial moves D(z)'s "
                  "poles by %.3g of their distance to the unit circle (over 1e-3)", s.pole_shift);
  } else {
    std::snprintf(buf, sizeof buf,
                  "stability from the closed loop's eigenvalues: rounding the characteristic polynomial moves the "
                  "boundary by %.3g (relative, over %.0e)", s.polynomial_error, kPolynomialRelativeTolerance);
  }
  return buf;
}

double ZWidth::HzOf(double theta) const { return theta / (2.0 * std::numbers::pi * period_s_); }

std::vector<Crossing> ZWidth::Crossings(double B) const {
  std::vector<Crossing> out;
  for (const Segment& s : segments_) {
    const double lo = std::min(s.Ba, s.Bb), hi = std::max(s.Ba, s.Bb);
    if (B < lo || B > hi) continue;
    auto g = [&](double t) { double b, k; Point(t, &b, &k); return b - B; };
    // Narrow the bracket to one cell of the tabulated grid (B is monotone on
    // the piece), so that Brent starts close to the root.
    double ta = s.ta, tb = s.tb, fa = s.Ba - B, fb = s.Bb - B;
    if (s.ib >= s.ia) {
      const bool inc = s.Bb > s.Ba;
      int lo = s.ia, hi = s.ib + 1;  // first grid index past B
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (inc ? grid_B_[mid] >= B : grid_B_[mid] <= B) hi = mid; else lo = mid + 1;
      }
      double ca = ta, cb = tb, ga = fa, gb = fb;
      if (lo <= s.ib) { cb = grid_theta_[lo]; gb = grid_B_[lo] - B; }
      if (lo > s.ia) { ca = grid_theta_[lo - 1]; ga = grid_B_[lo - 1] - B; }
      if (!(ga * gb > 0.0)) { ta = ca; tb = cb; fa = ga; fb = gb; }
    }
    const double t = BrentRoot(g, ta, tb, fa, fb, options_.theta_tolerance);
    double b, k;
    Point(t, &b, &k);
    // Reject a spurious "root" at a singularity of B(theta) (a zero of G_d).
    if (!std::isfinite(k) || std::abs(b - B) > 1e-6 * (std::abs(B) + std::abs(lo) + std::abs(hi) + 1e-12)) continue;
    // Direction (see the header): sign(Im V) x sign(B'(theta)); unknown at
    // an end of the piece, where B' vanishes (a tangency).
    const double iv = V(std::cos(t), std::sin(t)).imag();
    const bool at_end = std::min(t - s.ta, s.tb - t) <= 4.0 * options_.theta_tolerance;
    const int dir = (at_end || iv == 0.0 || s.Ba == s.Bb) ? 0 : ((s.Bb > s.Ba) == (iv > 0.0) ? 1 : -1);
    out.push_back({t, k, dir});
  }
  const double g1 = dW_pi_ - B * dV_pi_;  // g'(-1): the real root leaves through -1 when < 0
  const bool known = std::isfinite(g1) && std::abs(g1) > 1e-6 * (std::abs(dW_pi_) + std::abs(B * dV_pi_));
  out.push_back({std::numbers::pi, K_pi_at_zero_B_ - B * V_pi_, known ? (g1 < 0.0 ? 1 : -1) : 0});
  return out;
}

std::vector<double> ZWidth::CharacteristicPolynomial(double K, double B) const {
  // z^{d+1} D(z) F_d(z) + (K z F_d(z) + (B/T)(z - 1) F_n(z)) N(z)
  const int d = total_delay_;
  if (!has_filter_) {
    std::vector<double> p(d + 1 + sp_.denominator().size(), 0.0);
    for (size_t i = 0; i < sp_.denominator().size(); ++i) p[i + d + 1] += sp_.denominator()[i];
    const std::vector<double> ctrl = {-B / period_s_, K + B / period_s_};
    const std::vector<double> cn = PolyMul(ctrl, sp_.numerator());
    for (size_t i = 0; i < cn.size(); ++i) p[i] += cn[i];
    return p;
  }
  const std::vector<double> dfd = PolyMul(sp_.denominator(), fd_);
  std::vector<double> p(d + 1 + dfd.size(), 0.0);
  for (size_t i = 0; i < dfd.size(); ++i) p[i + d + 1] += dfd[i];
  std::vector<double> ctrl(fd_.size() + 1, 0.0);  // K z F_d + (B/T)(z - 1) F_n
  for (size_t i = 0; i < fd_.size(); ++i) ctrl[i + 1] += K * fd_[i];
  for (size_t i = 0; i < fn_.size(); ++i) { ctrl[i + 1] += B / period_s_ * fn_[i]; ctrl[i] -= B / period_s_ * fn_[i]; }
  const std::vector<double> cn = PolyMul(ctrl, sp_.numerator());
  for (size_t i = 0; i < cn.size(); ++i) p[i] += cn[i];
  return p;
}

bool ZWidth::IsStable(double K, double B) const { return UnstableRoots(K, B) == 0; }

int ZWidth::UnstableRoots(double K, double B) const {
  if (!use_polynomial_) {
    // The closed-loop state matrix (stability/closed_loop.h): K = 0 is 0+,
    // the integrator's eigenvalue at 1 deflated (it moves inside for K > 0).
    if (K < 0.0 && has_integrator_) return 1;
    if (K == 0.0) return RootsOutsideAtZeroK(B);
    return closed_loop_->RootsOutside(K, B, false);
  }
  return PolynomialStable(K, B) ? 0 : 1;
}

std::vector<double> ZWidth::ZeroKCandidates() const {
  std::vector<double> cand;
  auto Kof = [this](double t) { double b, k; Point(t, &b, &k); return k; };
  for (size_t i = 1; i < grid_theta_.size(); ++i) {
    if ((i & 255) == 0) PollCancel();  // model/cancel.h: a host's Ctrl-C
    if ((grid_K_[i - 1] > 0) != (grid_K_[i] > 0)) {
      const double t = BrentRoot(Kof, grid_theta_[i - 1], grid_theta_[i], grid_K_[i - 1], grid_K_[i],
                                 options_.theta_tolerance);
      double b, k;
      Point(t, &b, &k);
      if (b > 0.0 && std::isfinite(b)) cand.push_back(b);
    }
  }
  if (V_pi_ != 0.0 && K_pi_at_zero_B_ / V_pi_ > 0.0) cand.push_back(K_pi_at_zero_B_ / V_pi_);
  std::sort(cand.begin(), cand.end());
  return cand;
}

int ZWidth::RootsOutsideAtZeroK(double B) const {
  // K = 0+ (the integrator's eigenvalue at 1 deflated). Between two
  // candidates no root crosses the circle, so the count is the same for every
  // B there: one eigenvalue count per interval. Within 1e-9 of a candidate
  // (whose B is known to the theta tolerance) the count is taken at B itself.
  const bool deflate = has_integrator_;
  const auto it = std::upper_bound(zero_k_b_.begin(), zero_k_b_.end(), B);
  const bool near = (it != zero_k_b_.end() && std::abs(*it - B) <= 1e-9 * std::abs(*it)) ||
                    (it != zero_k_b_.begin() && std::abs(B - *(it - 1)) <= 1e-9 * std::abs(*(it - 1)));
  if (near || !(B >= 0.0) || !zero_k_counts_) return closed_loop_->RootsOutside(0.0, B, deflate);
  std::atomic<int>& slot = (*zero_k_counts_)[static_cast<size_t>(it - zero_k_b_.begin())];
  int c = slot.load(std::memory_order_relaxed);
  if (c < 0) {
    c = closed_loop_->RootsOutside(0.0, B, deflate);
    slot.store(c, std::memory_order_relaxed);
  }
  return c;
}

template <typename Stable>
bool ZWidth::ConfirmsEnd(double K_in, double K_out, double B, const Stable& stable) const {
  if (!use_polynomial_ && polynomial_verifies_ && PolynomialStable(K_in, B) && !PolynomialStable(K_out, B)) return true;
  return stable(K_in) == 0 && stable(K_out) != 0;
}

bool ZWidth::PolynomialStable(double K, double B) const {
  if (K > 0.0 || !has_integrator_) return AllRootsInsideUnitCircle(CharacteristicPolynomial(K, B));
  if (K < 0.0) return false;  // the integrator pole leaves through z = 1
  // K = 0+: the factor (z - 1) leaves z^{d+1} D1(z) F_d(z) + (B/T) F_n(z) N(z).
  // (The root at z = 1 moves inside for K > 0 when b + B F(1) > 0.)
  const int d = total_delay_;
  const std::vector<double> dfd = PolyMul(sp_.denominator_without_integrator(), fd_);
  const std::vector<double> fnn = PolyMul(fn_, sp_.numerator());
  std::vector<double> q(std::max(d + 1 + dfd.size(), fnn.size()), 0.0);
  for (size_t i = 0; i < dfd.size(); ++i) q[i + d + 1] += dfd[i];
  for (size_t i = 0; i < fnn.size(); ++i) q[i] += B / period_s_ * fnn[i];
  return AllRootsInsideUnitCircle(q);
}

bool BGridOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (!(std::isfinite(b_min) && b_min >= 0.0)) return bad("BGridOptions::b_min must be finite and >= 0");
  if (!std::isnan(b_max) && !(std::isfinite(b_max) && b_max >= b_min)) return bad("BGridOptions::b_max must be finite and >= BGridOptions::b_min");
  if (!std::isnan(b_step) && !(std::isfinite(b_step) && b_step > 0.0)) return bad("BGridOptions::b_step must be finite and > 0");
  if (!(b_points >= 2 && b_points <= kMaxBGridValues)) return bad("BGridOptions::b_points must be in [2, 1000000]");
  return true;
}

std::vector<double> MakeBGrid(const BGridOptions& o, double largest, double fallback, int num_delays) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  double hi = o.b_max;
  if (std::isnan(hi)) {
    hi = (largest > 0.0 && std::isfinite(largest)) ? 1.05 * largest : fallback;
    hi = std::max(hi, o.b_min);
  }
  const double nd = std::max(1, num_delays);
  double count;
  if (!std::isnan(o.b_step)) count = std::floor((hi - o.b_min) / o.b_step * (1.0 + 1e-12)) + 1.0;
  else count = hi > o.b_min ? o.b_points : 1.0;
  if (!(count * nd <= kMaxBGridValues)) {
    char buf[300];
    std::snprintf(buf, sizeof buf,
                  "the B grid would have %.3g values x %d delays, over the cap of %.0f: raise BGridOptions::b_step, "
                  "lower BGridOptions::b_points or narrow BGridOptions::b_min/BGridOptions::b_max",
                  count, num_delays, kMaxBGridValues);
    throw InputError(buf);
  }
  const long n = static_cast<long>(count);
  std::vector<double> g(n);
  for (long k = 0; k < n; ++k) {
    g[k] = std::isnan(o.b_step) ? (n == 1 ? o.b_min : o.b_min + (hi - o.b_min) * k / (n - 1))
                                : o.b_min + k * o.b_step;
  }
  return g;
}

double ZWidth::NoCrossingProbe(const std::vector<Crossing>& xs) const {
  // Far above every crossing's |K| (whatever its sign), so that a crossing
  // near K = 0 lost to rounding lies between 0+ and the probe.
  double k = 0.0;
  for (const Crossing& x : xs) if (std::isfinite(x.K)) k = std::max(k, std::abs(x.K));
  return k > 0.0 ? 2.0 * k : 1e6;
}

template <typename Stable>
CriticalPoint ZWidth::PointFrom(double B, const std::vector<Crossing>& xs, const Stable& stable, Check check) const {
  const bool verify = check == Check::kVerify;
  CriticalPoint cp;
  cp.B = B;
  // The paper's reading: the phase crossover with margin nearest 0 dB.
  double best_db = std::numeric_limits<double>::infinity();
  for (const Crossing& x : xs) {
    if (!(x.K > 0.0)) continue;
    const double db = std::abs(std::log(x.K));
    if (db < best_db) { best_db = db; cp.K_margin = x.K; cp.f_margin_hz = HzOf(x.theta); }
  }
  if (stable(0.0) != 0) {
    cp.unstable_at_zero_k = true;
    cp.K_cr = 0.0;
    cp.verified = true;
    return cp;
  }
  cp.K_cr = std::numeric_limits<double>::infinity();
  for (const Crossing& x : xs) {
    if (x.K > 0.0 && x.K < cp.K_cr) { cp.K_cr = x.K; cp.f_cr_hz = HzOf(x.theta); }
  }
  if (std::isinf(cp.K_cr)) {
    // No crossing with K > 0: every K > 0 is as stable as K -> 0+, unless a
    // crossing at K ~ 0 was lost to rounding (B on the K = 0 boundary, e.g.
    // exactly at B_max_from_zero): then nothing is stable.
    if (stable(NoCrossingProbe(xs)) != 0) {
      cp.K_cr = 0.0;
      cp.verified = false;
      return cp;
    }
    cp.verified = true;
    return cp;
  }
  cp.verified = !verify || !options_.verify ||
                ConfirmsEnd(cp.K_cr * (1.0 - 1e-6), cp.K_cr * (1.0 + 1e-6), B, stable);
  return cp;
}

double ZWidth::FindTransition(double lo, double hi, double f_lo, double f_hi) const {
  for (int it = 0; it < 60 && hi - lo > 1e-14 * std::max(1.0, hi); ++it) {
    const double mid = 0.5 * (lo + hi);
    const double f = ValueAt(mid).f_cr_hz;
    if (std::abs(std::log(f / f_lo)) < std::abs(std::log(f / f_hi))) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

template <typename Stable>
std::vector<KInterval> ZWidth::IntervalsFrom(double B, const std::vector<Crossing>& xs, const Stable& stable,
                                             Check check, bool use_directions) const {
  std::vector<Crossing> pos;
  for (const Crossing& x : xs) if (x.K > 0.0 && std::isfinite(x.K)) pos.push_back(x);
  std::sort(pos.begin(), pos.end(), [](const Crossing& a, const Crossing& b) { return a.K < b.K; });
  // Merge coincident crossings (a double root at one K); weight: how many
  // roots can cross the circle there (a conjugate pair at 0 < theta < pi, one
  // real root at theta = pi).
  // change: how the number of roots outside changes there, from the
  // directions (known: every merged crossing's direction is known).
  std::vector<Crossing> ks;
  std::vector<int> weight, change;
  std::vector<char> known;
  for (const Crossing& x : pos) {
    const int w = x.theta < std::numbers::pi ? 2 : 1;
    if (!ks.empty() && x.K - ks.back().K <= 1e-13 * x.K) {
      weight.back() += w;
      change.back() += w * x.direction;
      known.back() = known.back() && x.direction != 0;
      continue;
    }
    ks.push_back(x);
    weight.push_back(w);
    change.push_back(w * x.direction);
    known.push_back(x.direction != 0);
  }
  const double inf = std::numeric_limits<double>::infinity();
  const size_t n = ks.size();
  std::vector<KInterval> out;
  // Region i lies between bound(i) and bound(i + 1); bound(0) = 0, bound(n + 1) = inf.
  auto lo_of = [&](size_t i) { return i == 0 ? 0.0 : ks[i - 1].K; };
  auto hi_of = [&](size_t i) { return i == n ? inf : ks[i].K; };
  // Roots cross the circle only at crossings: a region after one with u
  // unstable roots has at least u - weight unstable, and is not tested while
  // that is positive (the eigenvalue test counts u; Schur-Cohn says u >= 1).
  // With the eigenvalue test the count is exact, and where every crossing's
  // direction is known it follows from the region before without a test:
  // count_i = count_{i-1} + change_{i-1} (the Nyquist count), so only K -> 0+
  // and the regions after a crossing of unknown direction are tested.
  const bool count = use_directions && !use_polynomial_;
  int unstable_at_least = 0, exact = -1;  // exact: the region's count, -1 not known
  for (size_t i = 0; i <= n; ++i) {
    if (i > 0) {
      unstable_at_least -= weight[i - 1];
      exact = (exact >= 0 && known[i - 1] && exact + change[i - 1] >= 0) ? exact + change[i - 1] : -1;
    }
    const double a = lo_of(i), b = hi_of(i);
    if (exact >= 0) {
      unstable_at_least = exact;
    } else {
      if (unstable_at_least > 0) continue;
      double probe;
      if (i == 0) probe = (n == 0 || count) ? 0.0 : 0.5 * b;  // K -> 0+ when there is no crossing at all
      else if (i == n) probe = 2.0 * a;
      else probe = std::sqrt(a * b);
      unstable_at_least = stable(probe);
      if (count) exact = unstable_at_least;
    }
    if (unstable_at_least != 0) continue;
    if (n == 0 && stable(NoCrossingProbe(xs)) != 0) continue;  // see PointFrom
    if (!out.empty() && out.back().K_hi == a) {  // a tangential crossing: both sides stable
      out.back().K_hi = b;
      out.back().f_hi_hz = i == n ? std::numeric_limits<double>::quiet_NaN() : HzOf(ks[i].theta);
      continue;
    }
    KInterval iv;
    iv.K_lo = a;
    iv.K_hi = b;
    if (i > 0) iv.f_lo_hz = HzOf(ks[i - 1].theta);
    if (i < n) iv.f_hi_hz = HzOf(ks[i].theta);
    out.push_back(iv);
    if (check == Check::kFirstOnly) return out;
  }
  bool all_ok = true;
  for (KInterval& iv : out) {
    bool ok = true;
    if (check == Check::kVerify && options_.verify) {
      if (iv.K_lo > 0.0) ok = ok && ConfirmsEnd(iv.K_lo * (1.0 + 1e-6), iv.K_lo * (1.0 - 1e-6), B, stable);
      if (std::isfinite(iv.K_hi)) ok = ok && ConfirmsEnd(iv.K_hi * (1.0 - 1e-6), iv.K_hi * (1.0 + 1e-6), B, stable);
    }
    iv.verified = ok;
    all_ok = all_ok && ok;
  }
  // An interval from the counts that the test does not confirm: the test at
  // every region decides instead.
  if (count && !all_ok) return IntervalsFrom(B, xs, stable, check, false);
  return out;
}

CriticalPoint ZWidth::At(double B) const {
  return PointFrom(B, Crossings(B), [&](double K) { return UnstableRoots(K, B); }, Check::kVerify);
}

std::vector<KInterval> ZWidth::StableIntervals(double B) const {
  return IntervalsFrom(B, Crossings(B), [&](double K) { return UnstableRoots(K, B); }, Check::kVerify);
}

CriticalPoint ZWidth::ValueAt(double B) const {
  return PointFrom(B, Crossings(B), [&](double K) { return UnstableRoots(K, B); }, Check::kValuesOnly);
}

bool ZWidth::AnyStable(double B) const {
  return !IntervalsFrom(B, Crossings(B), [&](double K) { return UnstableRoots(K, B); }, Check::kFirstOnly).empty();
}

ZWidth::Row ZWidth::RowAt(double B) const {
  // The verification of K_CR and of the first interval's upper end test the
  // same K values: each K is tested once (B is fixed, so K decides).
  std::vector<std::pair<double, int>> tested;
  auto stable = [&](double K) {
    for (const auto& [k, s] : tested) if (k == K) return s;
    const int s = UnstableRoots(K, B);
    tested.push_back({K, s});
    return s;
  };
  const std::vector<Crossing> xs = Crossings(B);
  Row r;
  r.point = PointFrom(B, xs, stable, Check::kVerify);
  r.intervals = IntervalsFrom(B, xs, stable, Check::kVerify);
  return r;
}

double ZWidth::StableBBound() const {
  // A stable K interval is bounded above by a crossing with K > 0 (for large K,
  // d + 1 roots leave through infinity), so past the largest B of the curve
  // with K > 0 nothing is stable. On each monotone piece the largest B with
  // K > 0 is at an end of the piece or where K(theta) changes sign.
  double bound = 0.0;
  auto Kof = [this](double t) { double b, k; Point(t, &b, &k); return k; };
  for (const Segment& sg : segments_) {
    const double ka = Kof(sg.ta), kb = Kof(sg.tb);
    if (ka > 0.0 && std::isfinite(sg.Ba)) bound = std::max(bound, sg.Ba);
    if (kb > 0.0 && std::isfinite(sg.Bb)) bound = std::max(bound, sg.Bb);
  }
  for (size_t i = 1; i < grid_theta_.size(); ++i) {
    if (grid_K_[i - 1] > 0.0 && std::isfinite(grid_B_[i - 1])) bound = std::max(bound, grid_B_[i - 1]);
    if ((grid_K_[i - 1] > 0) != (grid_K_[i] > 0)) {
      const double t = BrentRoot(Kof, grid_theta_[i - 1], grid_theta_[i], grid_K_[i - 1], grid_K_[i],
                                 options_.theta_tolerance);
      double b, k;
      Point(t, &b, &k);
      if (std::isfinite(b)) bound = std::max(bound, b);
    }
  }
  // The theta = pi line K = K_pi - B V_pi has K > 0 up to B = K_pi / V_pi when
  // V_pi > 0; otherwise for every large B, and no bound is proven.
  if (V_pi_ > 0.0) {
    if (K_pi_at_zero_B_ > 0.0) bound = std::max(bound, K_pi_at_zero_B_ / V_pi_);
  } else if (K_pi_at_zero_B_ > 0.0 || V_pi_ < 0.0) {
    return std::numeric_limits<double>::infinity();
  }
  return bound;
}

DelaySummary ZWidth::Summarize() const {
  DelaySummary s;
  s.delay_samples = total_delay_;
  s.polynomial_test = use_polynomial_;
  s.polynomial_error = polynomial_error_;
  s.pole_shift = sp_.denominator_pole_shift();
  s.conditioning = sp_.conditioning();
  s.conditioning_warning = ConditioningWarning(use_polynomial_, s.conditioning);
  const CriticalPoint c0 = ValueAt(0.0);
  s.K_cr_at_zero_B = c0.K_cr;
  s.f_at_zero_B_hz = c0.f_cr_hz;
  const std::vector<double> cand = ZeroKBoundary(c0, &s);
  ScanStableB(cand, &s);
  if (c0.unstable_at_zero_k) return s;
  ScanKcrMax(c0, cand, &s);
  return s;
}

// B_max_from_zero and the B > 0 where the K = 0 boundary is crossed (sorted):
// where bands can start or end.
std::vector<double> ZWidth::ZeroKBoundary(const CriticalPoint& c0, DelaySummary* out) const {
  DelaySummary& s = *out;
  // B_max_from_zero: the first B > 0 on the K = 0 boundary where K -> 0+ turns unstable.
  const std::vector<double>& cand = zero_k_b_;
  if (c0.unstable_at_zero_k) {
    s.B_max_from_zero = 0.0;
  } else {
    // The first candidate where K -> 0+ turns from stable to unstable. Right at
    // b the closed loop has a root on the circle: Schur-Cohn decides the sides
    // at b (1 -+ delta), with delta widened (below half the gap to the
    // neighbouring candidates) until they read stable below and unstable
    // above, since a high-order polynomial (long delay, heavy device) can
    // misjudge a root within ~1e-9 of the circle either way.
    for (size_t i = 0; i < cand.size() && std::isinf(s.B_max_from_zero); ++i) {
      const double b = cand[i];
      double gap = b;
      if (i > 0) gap = std::min(gap, b - cand[i - 1]);
      if (i + 1 < cand.size()) gap = std::min(gap, cand[i + 1] - b);
      for (double delta : {1e-9, 1e-7, 1e-5, 1e-3}) {
        if (delta * b >= 0.5 * gap && delta > 1e-9) break;
        const bool below = IsStable(0.0, b * (1.0 - delta)), above = IsStable(0.0, b * (1.0 + delta));
        if (below && !above) { s.B_max_from_zero = b; break; }
      }
    }
  }
  return cand;
}

// B_max and the reopened bands past B_max_from_zero.
void ZWidth::ScanStableB(const std::vector<double>& cand, DelaySummary* out) const {
  DelaySummary& s = *out;
  // B_max and the reopened bands: scan B up to the bound past which no crossing
  // with K > 0 exists, uniformly, geometrically, and at both sides of every
  // fold of the curve and every K = 0 point (where bands start or end).
  const double bound = StableBBound();
  if (bound > 0.0 && std::isfinite(bound)) {
    std::vector<double> bs;
    const int n_scan = 1000;
    for (int i = 0; i <= n_scan; ++i) bs.push_back(bound * i / n_scan);
    for (int i = 0; i <= n_scan; ++i) bs.push_back(bound * std::pow(1e-6, 1.0 - double(i) / n_scan));
    auto add = [&](double b) {
      if (b > 0.0 && b <= bound && std::isfinite(b)) { bs.push_back(b * (1.0 - 1e-7)); bs.push_back(b * (1.0 + 1e-7)); }
    };
    for (double b : cand) add(b);
    for (const Segment& sg : segments_) { add(sg.Ba); add(sg.Bb); }
    if (std::isfinite(s.B_max_from_zero)) add(s.B_max_from_zero);
    bs.push_back(bound * (1.0 + 1e-9));
    std::sort(bs.begin(), bs.end());
    bs.erase(std::unique(bs.begin(), bs.end()), bs.end());
    std::vector<char> st(bs.size());
    std::vector<double> kmax(bs.size(), 0.0);
    for (size_t i = 0; i < bs.size(); ++i) {
      const std::vector<KInterval> iv = IntervalsFrom(bs[i], Crossings(bs[i]), [&](double K) { return UnstableRoots(K, bs[i]); },
                                                      Check::kValuesOnly);
      st[i] = !iv.empty();
      for (const KInterval& v : iv) kmax[i] = std::max(kmax[i], std::isfinite(v.K_hi) ? v.K_hi : v.K_lo);
    }
    auto edge = [&](double lo, double hi, bool lo_stable) {  // bisection of "some K stable"
      for (int it = 0; it < 80 && hi - lo > 1e-14 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (AnyStable(mid) == lo_stable ? lo : hi) = mid;
      }
      return 0.5 * (lo + hi);
    };
    s.B_max = 0.0;
    for (size_t i = bs.size(); i-- > 0;) {
      if (st[i]) {
        s.B_max = i + 1 < bs.size() ? edge(bs[i], bs[i + 1], true) : bs[i];
        break;
      }
    }
    // Bands past B_max_from_zero.
    const double b0 = std::isfinite(s.B_max_from_zero) ? s.B_max_from_zero : bound;
    for (size_t i = 0; i < bs.size(); ++i) {
      if (!st[i] || bs[i] <= b0) continue;
      ReopenedBand band;
      band.B_lo = (i > 0 && !st[i - 1] && bs[i - 1] > b0) ? edge(bs[i - 1], bs[i], false) : b0;
      size_t j = i;
      while (j + 1 < bs.size() && st[j + 1]) { band.K_max = std::max(band.K_max, kmax[j]); ++j; }
      band.K_max = std::max(band.K_max, kmax[j]);
      band.B_hi = j + 1 < bs.size() ? edge(bs[j], bs[j + 1], true) : bs[j];
      s.reopened_bands.push_back(band);
      i = j;
    }
  } else {
    s.B_max = std::isfinite(s.B_max_from_zero) ? s.B_max_from_zero : s.B_max;
  }
}

// K_CR^max (and where), and the transition B_t where f_CR jumps, on [0, B_max_from_zero).
void ZWidth::ScanKcrMax(const CriticalPoint& c0, const std::vector<double>& cand, DelaySummary* out) const {
  DelaySummary& s = *out;
  // Scan [0, B_max_from_zero) for the jump of f_CR and the maximum of K_CR.
  const double b_hi = std::isfinite(s.B_max_from_zero) ? s.B_max_from_zero : (cand.empty() ? 1.0 : 2.0 * cand.back());
  const int n = 200;
  double prev_f = c0.f_cr_hz, prev_b = 0.0;
  s.K_cr_max = c0.K_cr;
  s.B_at_K_cr_max = 0.0;
  // The last point lies just below b_hi, so that a jump in the last cell
  // (a branch taking over just before the interval from 0+ closes) is seen.
  for (int i = 1; i <= n; ++i) {
    const double b = i < n ? b_hi * i / n : b_hi * (1.0 - 1e-6);
    const CriticalPoint cp = ValueAt(b);
    if (!(cp.K_cr > 0.0) || std::isinf(cp.K_cr)) break;
    if (cp.K_cr > s.K_cr_max) { s.K_cr_max = cp.K_cr; s.B_at_K_cr_max = b; }
    if (std::abs(std::log(cp.f_cr_hz / prev_f)) > std::log(1.5)) {
      const double bt = FindTransition(prev_b, b, prev_f, cp.f_cr_hz);
      // Beyond FindTransition's final bracket (1e-14 absolute below B = 1).
      const double eps = std::max(1e-9 * bt, 2e-14 * std::max(1.0, bt));
      const CriticalPoint before = ValueAt(bt - eps), after = ValueAt(bt + eps);
      for (const CriticalPoint& p : {before, after}) {
        if (p.K_cr > s.K_cr_max) { s.K_cr_max = p.K_cr; s.B_at_K_cr_max = p.B; }
      }
      // A jump only when f_CR really jumps at bt: a smooth but steep f_CR(B)
      // can also change by 1.5x between two scan points.
      if (std::abs(std::log(after.f_cr_hz / before.f_cr_hz)) > std::log(1.5)) {
        s.frequency_jumps.push_back({bt, before.K_cr, after.K_cr, before.f_cr_hz, after.f_cr_hz});
      }
    }
    prev_f = cp.f_cr_hz;
    prev_b = b;
  }
  // B_t (the paper's section III): where K_CR(B) peaks as f_CR jumps: of
  // every jump, the one with the largest K_CR on either side.
  const FrequencyJump* peak = nullptr;
  for (const FrequencyJump& j : s.frequency_jumps) {
    if (!peak || std::max(j.K_before, j.K_after) > std::max(peak->K_before, peak->K_after)) peak = &j;
  }
  if (peak) {
    s.has_transition = true;
    s.B_t = peak->B;
    s.f_before_hz = peak->f_before_hz;
    s.f_after_hz = peak->f_after_hz;
  }
  // Refine an interior maximum that is not at the transition.
  if (s.B_at_K_cr_max > 0.0 && (!s.has_transition || std::abs(s.B_at_K_cr_max - s.B_t) > b_hi / n)) {
    const double lo = std::max(0.0, s.B_at_K_cr_max - b_hi / n), hi = s.B_at_K_cr_max + b_hi / n;
    double bm;
    const double km = LargestKcr(lo, hi, 1e-12 * b_hi, &bm);
    if (km > s.K_cr_max) { s.K_cr_max = km; s.B_at_K_cr_max = bm; }
  }
}

double ZWidth::LargestKcr(double lo, double hi, double tol, double* b_at) const {
  // The largest value the search evaluated, not the value at its last
  // midpoint: where K_CR(B) rises to a corner (the interval from K = 0+
  // closing at B_max_from_zero from below) the bracket closes on a
  // discontinuity, and its midpoint can lie past it (K_CR = 0 there).
  double best = -std::numeric_limits<double>::infinity(), best_b = std::numeric_limits<double>::quiet_NaN();
  auto k_of = [&](double b) {
    const double k = ValueAt(b).K_cr;
    if (k > best) { best = k; best_b = b; }
    return k;
  };
  k_of(internal::GoldenExtremum(k_of, lo, hi, 1.0, tol));
  if (b_at) *b_at = best_b;
  return best;
}

SummaryStd ZWidth::SummarizeNear(const DelaySummary& nom) const {
  SummaryStd q;  // here: the values, not their std
  q.K_cr_at_zero_B = ValueAt(0.0).K_cr;
  const double w = 0.02;
  if (nom.has_transition) {
    const double lo = nom.B_t * (1 - w), hi = nom.B_t * (1 + w);
    const double flo = ValueAt(lo).f_cr_hz, fhi = ValueAt(hi).f_cr_hz;
    if (std::abs(std::log(flo / nom.f_before_hz)) < 0.3 && std::abs(std::log(fhi / nom.f_after_hz)) < 0.3) {
      q.B_t = FindTransition(lo, hi, nom.f_before_hz, nom.f_after_hz);
    }
  }
  const bool at_corner = nom.has_transition && std::abs(nom.B_at_K_cr_max - nom.B_t) <= 1e-6 * nom.B_t;
  if (at_corner) {
    if (std::isfinite(q.B_t)) {
      const double eps = 1e-9 * q.B_t;
      q.K_cr_max = std::max(ValueAt(q.B_t - eps).K_cr, ValueAt(q.B_t + eps).K_cr);
    }
  } else if (nom.B_at_K_cr_max > 0.0) {
    const double lo = nom.B_at_K_cr_max * (1 - w), hi = nom.B_at_K_cr_max * (1 + w);
    q.K_cr_max = LargestKcr(lo, hi, 1e-12 * hi, nullptr);
  } else {
    q.K_cr_max = q.K_cr_at_zero_B;
  }
  if (std::isfinite(nom.B_max) && nom.B_max > 0.0) {
    double lo = nom.B_max * (1 - w), hi = nom.B_max * (1 + w);
    if (AnyStable(lo) && !AnyStable(hi)) {
      for (int it = 0; it < 80 && hi - lo > 1e-14 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (AnyStable(mid) ? lo : hi) = mid;
      }
      q.B_max = 0.5 * (lo + hi);
    }
  }
  return q;
}

}  // namespace zwidth::stability
