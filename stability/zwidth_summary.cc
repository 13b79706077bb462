// The Z-width's summary of one delay (Summarize: K_CR(0), B_max, the
// reopened bands, K_CR^max and the transition B_t) and its re-evaluation near
// a nominal summary (SummarizeNear, for the std band): scans over B of the
// values zwidth.cc computes at one B (ValueAt, AnyStable, IntervalValues).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "stability/numerics_internal.h"
#include "stability/zwidth.h"

namespace zwidth::stability {

double ZWidth::FindTransition(double lo, double hi, double f_lo, double f_hi) const {
  for (int it = 0; it < 60 && hi - lo > 1e-14 * std::max(1.0, hi); ++it) {
    const double mid = 0.5 * (lo + hi);
    const double f = ValueAt(mid).f_cr_hz;
    if (std::abs(std::log(f / f_lo)) < std::abs(std::log(f / f_hi))) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
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
      const double t = internal::BrentRoot(Kof, grid_theta_[i - 1], grid_theta_[i], grid_K_[i - 1], grid_K_[i],
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
      const std::vector<KInterval> iv = IntervalValues(bs[i]);
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
