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
#include "stability/numerics_internal.h"
#include "stability/schur_cohn.h"
#include <Eigen/Eigenvalues>

namespace zwidth::stability {

using internal::BrentRoot;
using internal::PolyMul;

bool BoundaryOptions::IsValid(std::string* why) const {
  auto bad = [&](const char* m) { if (why) *why = std::string("BoundaryOptions::") + m; return false; };
  if (min_grid_points < 64) return bad("min_grid_points must be >= 64");
  if (grid_points_per_delay < 8) return bad("grid_points_per_delay must be >= 8");
  // The theta grid holds max(min_grid_points, grid_points_per_delay x (delay + order)) points, each a few
  // complex values: min_grid_points = 10**9 took every GiB and the OOM killer ended Python. 2^20 points
  // took 0.32 s and 32 MB more than the default (the default 2048 resolves every crossing: they are
  // refined by Brent's method).
  if (min_grid_points > (1 << 20)) return bad("min_grid_points must be at most 2**20 (1048576)");
  if (grid_points_per_delay > 1024) return bad("grid_points_per_delay must be at most 1024 (the default is 64)");
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

// g'(-1) = dW/dx - B dV/dx on the real axis at x = -1 (the sign of the real
// root's motion at theta = pi, in K and in B), nan where rounding hides it.
double SlopeAtMinusOne(double dW, double dV, double B) {
  const double g1 = dW - B * dV;
  const bool known = std::isfinite(g1) && std::abs(g1) > 1e-6 * (std::abs(dW) + std::abs(B * dV));
  return known ? g1 : std::numeric_limits<double>::quiet_NaN();
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
  zero_k_b_ = ZeroKCandidates(&zero_k_change_);
  zero_k_counts_ = std::make_shared<std::vector<std::atomic<int>>>(zero_k_b_.size() + 1);
  for (std::atomic<int>& c : *zero_k_counts_) c.store(-1);
  count_by_crossings_ = !use_polynomial_ && sp_.conditioning().eigenvalue_shift > kEigenvalueShiftWarning;
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
  const double g1 = SlopeAtMinusOne(dW_pi_, dV_pi_, B);  // the real root leaves through -1 when < 0
  out.push_back({std::numbers::pi, K_pi_at_zero_B_ - B * V_pi_, std::isnan(g1) ? 0 : (g1 < 0.0 ? 1 : -1)});
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
    if (count_by_crossings_) {
      const int c = CrossingCount(K, B);
      if (c >= 0) return c;
    }
    return closed_loop_->RootsOutside(K, B, false);
  }
  return PolynomialStable(K, B) ? 0 : 1;
}

int ZWidth::CrossingCount(double K, double B) const {
  // The roots cross the circle only at the crossings, each in its known
  // direction (Crossings): from K = 0+ (the eigenvalues at K = 0, where the
  // roots are the loop's at B alone and lie as far from the circle as the
  // plant's poles) to K the count changes by weight x direction at each.
  std::vector<Crossing> xs = Crossings(B);
  std::sort(xs.begin(), xs.end(), [](const Crossing& a, const Crossing& b) { return a.K < b.K; });
  const int order = closed_loop_->order();
  int count = RootsOutsideAtZeroK(B);
  for (const Crossing& x : xs) {
    if (!(x.K > 0.0) || !std::isfinite(x.K)) continue;
    if (std::abs(x.K - K) <= 1e-12 * K) return -1;  // on the boundary: the eigenvalues decide
    if (x.K > K) break;
    const int w = x.theta < std::numbers::pi ? 2 : 1;
    count = internal::PropagateCount(count, w * x.direction, x.direction != 0, order);
    if (count < 0) return -1;
  }
  return count;
}

std::vector<double> ZWidth::ZeroKCandidates(std::vector<int>* changes) const {
  // Each B with its change of the count at K = 0+ as B grows past it: the
  // roots solve g(z) = W - B V = K, so at fixed K dz/dB = V / g'(z), and on
  // the circle at a boundary point (dg/dtheta = B'(theta) V + K'(theta)) they
  // move outward iff -Im V K'(theta) > 0: a pair, +-2. At theta = pi the real
  // root moves outward iff V(pi) / g'(-1) < 0: +-1. 0 where the sign is not
  // clear (Im V or g'(-1) lost to rounding).
  std::vector<std::pair<double, int>> cand;
  auto Kof = [this](double t) { double b, k; Point(t, &b, &k); return k; };
  for (size_t i = 1; i < grid_theta_.size(); ++i) {
    if ((i & 255) == 0) PollCancel();  // model/cancel.h: a host's Ctrl-C
    if ((grid_K_[i - 1] > 0) != (grid_K_[i] > 0)) {
      const double t = BrentRoot(Kof, grid_theta_[i - 1], grid_theta_[i], grid_K_[i - 1], grid_K_[i],
                                 options_.theta_tolerance);
      double b, k;
      Point(t, &b, &k);
      if (!(b > 0.0 && std::isfinite(b))) continue;
      const std::complex<double> v = V(std::cos(t), std::sin(t));
      const bool k_rises = grid_K_[i] > grid_K_[i - 1];
      const bool known = std::abs(v.imag()) > 1e-9 * std::abs(v);
      cand.push_back({b, known ? (((v.imag() > 0.0) == k_rises) ? -2 : 2) : 0});
    }
  }
  if (V_pi_ != 0.0 && K_pi_at_zero_B_ / V_pi_ > 0.0) {
    const double b = K_pi_at_zero_B_ / V_pi_;
    const double g1 = SlopeAtMinusOne(dW_pi_, dV_pi_, b);
    cand.push_back({b, std::isnan(g1) ? 0 : ((V_pi_ / g1 < 0.0) ? 1 : -1)});
  }
  std::sort(cand.begin(), cand.end());
  std::vector<double> bs;
  changes->clear();
  for (const auto& [b, c] : cand) { bs.push_back(b); changes->push_back(c); }
  return bs;
}

int ZWidth::DirectZeroKCount(size_t slot) const {
  // A B inside the slot's interval, away from its ends.
  const size_t n = zero_k_b_.size();
  double B = 0.0;
  if (n > 0) {
    if (slot == 0) B = 0.5 * zero_k_b_[0];
    else if (slot == n) B = 2.0 * zero_k_b_[n - 1];
    else B = 0.5 * (zero_k_b_[slot - 1] + zero_k_b_[slot]);
  }
  return closed_loop_->RootsOutside(0.0, B, has_integrator_);
}

void ZWidth::FillZeroKBlock(size_t block) const {
  // The block's first slot and the next block's first are counted by the
  // eigenvalues; the slots between follow from the first by the changes of
  // the crossings between them, kept only when every change is known, every
  // count stays in [0, order] and the sum reaches the next block's count
  // (internal::PropagateCounts); else each slot is counted when asked.
  std::vector<std::atomic<int>>& slots = *zero_k_counts_;
  const size_t base = block * kZeroKBlock, last = slots.size() - 1;
  auto direct = [&](size_t i) {
    int c = slots[i].load(std::memory_order_relaxed);
    if (c < 0) { c = DirectZeroKCount(i); slots[i].store(c, std::memory_order_relaxed); }
    return c;
  };
  const int c = direct(base);
  if (base == last) return;
  const size_t next = std::min(base + kZeroKBlock, last);
  const int c_next = direct(next);
  // At K = 0+ the integrator's root is deflated: one root fewer.
  const int order = closed_loop_->order() - (has_integrator_ ? 1 : 0);
  const std::vector<int> changes(zero_k_change_.begin() + base, zero_k_change_.begin() + next);
  std::vector<int> counts;
  if (!internal::PropagateCounts(c, c_next, changes, order, &counts)) return;
  for (size_t j = base + 1; j < next; ++j) slots[j].store(counts[j - base - 1], std::memory_order_relaxed);
}

int ZWidth::RootsOutsideAtZeroK(double B) const {
  // K = 0+ (the integrator's eigenvalue at 1 deflated). Between two
  // candidates no root crosses the circle, so the count is the same for every
  // B there: counted once per interval (FillZeroKBlock: by the eigenvalues at
  // every kZeroKBlock-th, by the crossings' directions between). Within 1e-9
  // of a candidate (whose B is known to the theta tolerance) the count is
  // taken at B itself.
  const bool deflate = has_integrator_;
  const auto it = std::upper_bound(zero_k_b_.begin(), zero_k_b_.end(), B);
  const bool near = (it != zero_k_b_.end() && std::abs(*it - B) <= 1e-9 * std::abs(*it)) ||
                    (it != zero_k_b_.begin() && std::abs(B - *(it - 1)) <= 1e-9 * std::abs(*(it - 1)));
  if (near || !(B >= 0.0) || !zero_k_counts_) return closed_loop_->RootsOutside(0.0, B, deflate);
  const size_t i = static_cast<size_t>(it - zero_k_b_.begin());
  std::atomic<int>& slot = (*zero_k_counts_)[i];
  int c = slot.load(std::memory_order_relaxed);
  if (c >= 0) return c;
  FillZeroKBlock(i / kZeroKBlock);
  c = slot.load(std::memory_order_relaxed);
  if (c < 0) {  // the block's directions did not add up: counted here
    c = DirectZeroKCount(i);
    slot.store(c, std::memory_order_relaxed);
  }
  return c;
}

template <typename Stable>
bool ZWidth::ConfirmsEnd(double K_in, double K_out, double B, const Stable& stable, double gap) const {
  if (!use_polynomial_ && polynomial_verifies_ && PolynomialStable(K_in, B) && !PolynomialStable(K_out, B)) return true;
  if (!count_by_crossings_) return stable(K_in) == 0 && stable(K_out) != 0;
  // stable(K) counts the crossings themselves here: the eigenvalues verify.
  const double K = 0.5 * (K_in + K_out), side = K_out > K ? 1.0 : -1.0;
  for (double delta : {1e-6, 1e-5, 1e-4, 1e-3}) {
    if (delta > 1e-6 && delta >= 0.5 * gap) break;
    if (closed_loop_->RootsOutside(K * (1.0 - side * delta), B, false) == 0 &&
        closed_loop_->RootsOutside(K * (1.0 + side * delta), B, false) != 0) return true;
  }
  return false;
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

namespace {

// The relative distance from K to its nearest other crossing with K > 0
// (ConfirmsEnd's bound on how far it may probe); inf when there is none.
double RelativeGap(double K, const std::vector<Crossing>& xs) {
  double gap = std::numeric_limits<double>::infinity();
  for (const Crossing& x : xs) {
    if (!(x.K > 0.0) || !std::isfinite(x.K)) continue;
    const double g = std::abs(x.K - K) / K;
    if (g > 1e-13) gap = std::min(gap, g);
  }
  return gap;
}

}  // namespace

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
                ConfirmsEnd(cp.K_cr * (1.0 - 1e-6), cp.K_cr * (1.0 + 1e-6), B, stable, RelativeGap(cp.K_cr, xs));
  return cp;
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
      exact = internal::PropagateCount(exact, change[i - 1], known[i - 1], closed_loop_->order());
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
      if (iv.K_lo > 0.0) {
        ok = ok && ConfirmsEnd(iv.K_lo * (1.0 + 1e-6), iv.K_lo * (1.0 - 1e-6), B, stable, RelativeGap(iv.K_lo, xs));
      }
      if (std::isfinite(iv.K_hi)) {
        ok = ok && ConfirmsEnd(iv.K_hi * (1.0 - 1e-6), iv.K_hi * (1.0 + 1e-6), B, stable, RelativeGap(iv.K_hi, xs));
      }
    }
    iv.verified = ok;
    all_ok = all_ok && ok;
  }
  // An interval from the counts that the test does not confirm: the test at
  // every region decides instead (not where the crossings are what the
  // test counts, count_by_crossings_: the ends stay unverified).
  if (count && !all_ok && !count_by_crossings_) return IntervalsFrom(B, xs, stable, check, false);
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

std::vector<KInterval> ZWidth::IntervalValues(double B) const {
  return IntervalsFrom(B, Crossings(B), [&](double K) { return UnstableRoots(K, B); }, Check::kValuesOnly);
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

std::vector<KInterval> IntersectIntervals(const std::vector<KInterval>& a, const std::vector<KInterval>& b) {
  std::vector<KInterval> out;
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    KInterval r;
    r.K_lo = std::max(a[i].K_lo, b[j].K_lo);
    r.f_lo_hz = a[i].K_lo >= b[j].K_lo ? a[i].f_lo_hz : b[j].f_lo_hz;
    r.K_hi = std::min(a[i].K_hi, b[j].K_hi);
    r.f_hi_hz = a[i].K_hi <= b[j].K_hi ? a[i].f_hi_hz : b[j].f_hi_hz;
    r.verified = a[i].verified && b[j].verified;
    if (r.K_hi > r.K_lo) out.push_back(r);
    (a[i].K_hi < b[j].K_hi ? i : j)++;
  }
  return out;
}

}  // namespace zwidth::stability
