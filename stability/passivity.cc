#include "stability/passivity.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <utility>

#include "model/error.h"
#include "stability/numerics_internal.h"

namespace zwidth::stability {

bool PassivityOptions::IsValid(std::string* why) const {
  auto bad = [&](const char* m) { if (why) *why = std::string("PassivityOptions::") + m; return false; };
  if (min_grid_points < 64) return bad("min_grid_points must be >= 64");
  if (grid_points_per_delay < 8) return bad("grid_points_per_delay must be >= 8");
  if (!(theta_tolerance > 0.0 && theta_tolerance < 1e-3)) return bad("theta_tolerance must be in (0, 1e-3)");
  return true;
}

Passivity::Passivity(double b_phys, double period_s, int total_delay, const LoopOptions& loop,
                     const PassivityOptions& options)
    : b_(b_phys), T_(period_s), D_(total_delay), loop_(loop), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw InputError("passivity options: " + why);
  if (!loop_.IsValid(&why)) throw InputError("loop options: " + why);
  if (!(std::isfinite(b_) && b_ > 0.0)) throw InputError("passivity: the physical damping b must be > 0");
  if (!(std::isfinite(T_) && T_ > 0.0)) throw InputError("passivity: the period must be > 0");
  if (D_ < 0) throw InputError("passivity: the delay must be >= 0");
  const int order = static_cast<int>(std::max(loop_.filter_a.size(), loop_.filter_b.size()));
  const int n = std::max(options_.min_grid_points, options_.grid_points_per_delay * (2 * D_ + 2 + order));
  th_.resize(n + 1);
  P_.resize(n + 1);
  R_.resize(n + 1);
  inv_P_.resize(n + 1);
  upper_penalty_.resize(n + 1);
  lower_penalty_.resize(n + 1);
  const double inf = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i) {
    th_[i] = std::numbers::pi * i / n;
    PR(th_[i], &P_[i], &R_[i]);
    inv_P_[i] = P_[i] != 0.0 ? 1.0 / P_[i] : 0.0;
    upper_penalty_[i] = P_[i] > 0.0 ? 0.0 : inf;
    lower_penalty_[i] = P_[i] < 0.0 ? 0.0 : inf;
    if (P_[i] == 0.0) zero_P_.push_back(i);
  }
  // Blocks of the grid with the bounds of their lines u_i(B) = a_i + s_i B,
  // a_i = b/P_i, s_i = R_i/P_i (P_i > 0; l alike where P_i < 0), and of the
  // steps between neighbours of one sign (a candidate's reach is at most the
  // larger of its two steps), the neighbours just outside the block included.
  const size_t m = th_.size(), size = 64;
  for (size_t first = 0; first < m; first += size) {
    Block bk;
    bk.first = first;
    bk.last = std::min(m, first + size);
    for (size_t i = bk.first; i < bk.last; ++i) {
      if (P_[i] == 0.0) continue;
      LineBounds& lb = P_[i] > 0.0 ? bk.up : bk.down;
      const double a = b_ * inv_P_[i], sl = R_[i] * inv_P_[i];
      lb.any = true;
      lb.a_min = std::min(lb.a_min, a);
      lb.a_max = std::max(lb.a_max, a);
      lb.s_min = std::min(lb.s_min, sl);
      lb.s_max = std::max(lb.s_max, sl);
      lb.a_abs = std::max(lb.a_abs, std::abs(a));
      lb.s_abs = std::max(lb.s_abs, std::abs(sl));
    }
    // A point of one sign next to one of another sign (or P = 0): its block
    // holds a candidate of infinite reach, and is always scanned.
    for (size_t i = bk.first; i < bk.last; ++i) {
      if (P_[i] == 0.0) continue;
      const bool pos = P_[i] > 0.0;
      auto other = [&](size_t j) { return P_[j] == 0.0 || (P_[j] > 0.0) != pos; };
      if ((i > 0 && other(i - 1)) || (i + 1 < m && other(i + 1))) (pos ? bk.up : bk.down).edge = true;
    }
    for (size_t i = bk.first > 0 ? bk.first - 1 : 0; i + 1 < m && i < bk.last; ++i) {
      if (P_[i] == 0.0 || (P_[i] > 0.0) != (P_[i + 1] > 0.0) || P_[i + 1] == 0.0) continue;
      LineBounds& lb = P_[i] > 0.0 ? bk.up : bk.down;
      lb.da_max = std::max(lb.da_max, std::abs(b_ * inv_P_[i + 1] - b_ * inv_P_[i]));
      lb.ds_max = std::max(lb.ds_max, std::abs(R_[i + 1] * inv_P_[i + 1] - R_[i] * inv_P_[i]));
    }
    blocks_.push_back(bk);
  }
}

void Passivity::PR(double theta, double* P, double* R) const {
  // P = (T/2) sin((2D+1) theta/2) / sin(theta/2), the Dirichlet kernel, with its limit 2D+1 at 0.
  const double h = 0.5 * theta;
  const double sh = std::sin(h);
  *P = std::abs(sh) < 1e-300 ? 0.5 * T_ * (2 * D_ + 1) : 0.5 * T_ * std::sin((2 * D_ + 1) * h) / sh;
  std::complex<double> F = 1.0;
  if (loop_.HasFilter()) {
    const std::complex<double> zi = std::polar(1.0, -theta);
    std::complex<double> nb = 0.0, na = 0.0;
    for (size_t i = loop_.filter_b.size(); i-- > 0;) nb = nb * zi + loop_.filter_b[i];
    for (size_t i = loop_.filter_a.size(); i-- > 0;) na = na * zi + loop_.filter_a[i];
    F = nb / na;
  }
  *R = (std::polar(1.0, -(D_ + 1) * theta) * F).real();
}

double Passivity::Rhs(double K, double B, double theta) const {
  double P, R;
  PR(theta, &P, &R);
  return K * P - B * R;
}

namespace {

// A grid local extremum whose refinement (on its two neighbouring cells) could
// move the bound. value: the grid value (signed so that smaller is better);
// reach: how far below it a refinement could plausibly go. Through the three
// grid points the parabola's vertex lies (q - p)^2 / (8 (p + q)) <= (p + q)/8
// below the middle value (p, q >= 0 its rises to the neighbours); reach is four
// times that, (p + q)/2, so a candidate is refined unless even a much sharper
// dip than the grid shows could not beat the best refined value. Next to a
// grid point where the bound does not apply (the other sign of P, or P = 0)
// the function is not smooth across the cell, and reach is infinite: such a
// candidate is always refined. This is a bound on what the grid can resolve,
// not a proof: a dip more than four times deeper than the parabola (a feature
// narrower than the grid's cells) is skipped, as the refinement on two cells
// would miss a minimum that the grid does not show at all.
struct Candidate {
  size_t i;
  double value, reach;
};

double SignedReach(double left, double mid, double right) {
  if (!std::isfinite(left) || !std::isfinite(right)) return std::numeric_limits<double>::infinity();
  return 0.5 * (std::max(left - mid, 0.0) + std::max(right - mid, 0.0));
}

}  // namespace

PassiveInterval Passivity::At(double B) const {
  PassiveInterval out;
  bool zero_fail = false;  // P = 0 exactly at a grid point: the condition reads b + B R > 0
  for (size_t i : zero_P_) zero_fail = zero_fail || !(b_ + B * R_[i] > 0.0);
  // K_hi: the smallest upper bound; K_lo = max(0, the largest lower bound),
  // found as the smallest of minus the lower bounds below 0.
  double th_hi = std::numeric_limits<double>::quiet_NaN();
  const double hi = Smallest(B, 1.0, std::numeric_limits<double>::infinity(), &th_hi);
  out.K_lo = std::max(0.0, -Smallest(B, -1.0, 0.0, nullptr));
  out.theta_hi = th_hi;
  if (zero_fail || !(hi > out.K_lo)) {
    out.passive_set_empty = true;
    out.K_hi = 0.0;
    out.K_lo = 0.0;
    return out;
  }
  out.K_hi = hi;
  return out;
}

double Passivity::KHi(double B) const {
  for (size_t i : zero_P_) {
    if (!(b_ + B * R_[i] > 0.0)) return 0.0;
  }
  const double hi = Smallest(B, 1.0, std::numeric_limits<double>::infinity(), nullptr);
  if (!(hi > 0.0)) return 0.0;  // K_lo >= 0
  // The set is empty when K_lo >= hi, i.e. when minus a lower bound is <= -hi:
  // searched below a start just above -hi, so that -hi itself counts.
  const double start = std::nextafter(-hi, 0.0);
  return Smallest(B, -1.0, start, nullptr) < start ? 0.0 : hi;
}

// The bounds are v(theta) = sign (b + B R)/P where sign P > 0 (+inf elsewhere):
// sign +1 the upper bounds on K, sign -1 minus the lower ones.
//
// On the grid v is computed as sign (b + B R) times 1/P plus 0 or an infinite
// penalty (a division per point cost more than the rest of At); the values
// that reach the result are recomputed as sign (b + B R)/P, the products only
// choose the candidates: every grid local minimum of v (endpoints 0 and pi are
// exact grid points, taken as they are). A candidate is refined (Brent's
// parabolic search on its two neighbouring cells, ~10 evaluations where the
// golden section took ~48) unless its grid value less its reach
// cannot beat the best value so far: it could not change the result. Blocks
// of the grid are visited best bound first, and a block whose bound (its
// smallest v less the largest reach it allows; see Block) cannot beat the
// best value is not scanned. For the lower bounds (sign -1) every scanned
// point's value counts, not only the candidates' (the grid's largest lower
// bound, as before the pruning).
double Passivity::Smallest(double B, double sign, double best, double* theta) const {
  const double inf = std::numeric_limits<double>::infinity();
  auto v = [&](double t) {
    double P, R;
    PR(t, &P, &R);
    return sign * P > 0.0 ? sign * (b_ + B * R) / P : inf;
  };
  const size_t n = th_.size();
  const double* pen = sign > 0 ? upper_penalty_.data() : lower_penalty_.data();
  auto approx = [&](size_t i) { return sign * (b_ + B * R_[i]) * inv_P_[i] + pen[i]; };
  auto exact = [&](size_t i) { return sign * (b_ + B * R_[i]) / P_[i]; };
  const bool every_point = sign < 0;
  const double absB = std::abs(B);
  std::vector<std::pair<double, size_t>> order;  // (bound, block)
  order.reserve(blocks_.size());
  for (size_t k = 0; k < blocks_.size(); ++k) {
    const LineBounds& lb = sign > 0 ? blocks_[k].up : blocks_[k].down;
    if (!lb.any) continue;
    const double low = sign > 0 ? lb.a_min + (B >= 0.0 ? B * lb.s_min : B * lb.s_max)
                                : -(lb.a_max + (B >= 0.0 ? B * lb.s_max : B * lb.s_min));
    const double bound = lb.edge ? -inf : low - lb.da_max - absB * lb.ds_max - 1e-12 * (lb.a_abs + absB * lb.s_abs);
    order.push_back({std::isnan(bound) ? -inf : bound, k});  // NaN (an overflowed 1/P): scan it
  }
  std::sort(order.begin(), order.end());
  std::vector<Candidate> cands;
  for (const auto& [bound, k] : order) {
    if (bound >= best) break;
    cands.clear();
    for (size_t i = blocks_[k].first; i < blocks_[k].last; ++i) {
      const double vc = approx(i);
      if (!(vc < inf)) continue;
      if (every_point) best = std::min(best, exact(i));
      const double vl = i > 0 ? approx(i - 1) : inf, vr = i + 1 < n ? approx(i + 1) : inf;
      if ((i == 0 || vc <= vl) && (i + 1 == n || vc <= vr) && !(every_point && (i == 0 || i + 1 == n)))
        cands.push_back({i, vc, i > 0 && i + 1 < n ? SignedReach(vl, vc, vr) : 0.0});
    }
    std::sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) { return x.value < y.value; });
    for (const Candidate& c : cands) {
      if (c.value - c.reach >= best) continue;
      double t = th_[c.i], val = exact(c.i);
      if (c.i > 0 && c.i + 1 < n) {
        const double tt = internal::BrentExtremum(v, th_[c.i - 1], th_[c.i + 1], -1.0, options_.theta_tolerance);
        const double vv = v(tt);
        if (every_point || vv < val) { val = std::min(val, vv); t = tt; }
      }
      if (val < best) {
        best = val;
        if (theta) *theta = t;
      }
    }
  }
  return best;
}

}  // namespace zwidth::stability
