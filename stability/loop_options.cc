#include "stability/loop_options.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "stability/schur_cohn.h"

namespace zwidth::stability {

namespace {

bool AllFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

}  // namespace

bool LoopOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (filter_b.empty() != filter_a.empty()) return bad("filter_b and filter_a must both be given or both be empty");
  if (!filter_b.empty()) {
    if (filter_b.size() > 32) return bad("filter_b has more than 32 coefficients");
    if (filter_a.size() > 32) return bad("filter_a has more than 32 coefficients");
    if (!AllFinite(filter_b)) return bad("filter_b has a coefficient that is not finite");
    if (!AllFinite(filter_a)) return bad("filter_a has a coefficient that is not finite");
    // Beyond it the sums and products of the loop's polynomials overflow.
    for (const std::vector<double>* c : {&filter_b, &filter_a}) {
      for (double v : *c) {
        if (std::abs(v) > kMaxLoopValue) return bad("a filter coefficient exceeds 1e12 in magnitude");
      }
    }
    if (filter_a[0] != 1.0) return bad("filter_a: a0 must be 1 (divide every coefficient by a0)");
    // Poles: roots of z^m + a1 z^{m-1} + ... + am, i.e. the polynomial with
    // z^0 coefficient am (reversed a).
    std::vector<double> den(filter_a.rbegin(), filter_a.rend());
    while (den.size() > 1 && den.front() == 0.0) den.erase(den.begin());  // poles at 0
    if (den.size() > 1 && !AllRootsInsideUnitCircle(den)) {
      return bad("filter_a: the filter has a pole on or outside the unit circle (it must be stable)");
    }
    double nb = 0.0, na = 0.0;
    for (double v : filter_b) nb += v;
    for (double v : filter_a) na += v;
    if (!(nb / na > 0.0)) return bad("filter_b/filter_a: the DC gain F(1) must be > 0 (a velocity filter passes DC)");
  }
  if (!(hand.M >= 0.0 && hand.M <= kMaxLoopValue)) return bad("hand.M must lie in [0, 1e12] (SI)");
  if (!(hand.B >= 0.0 && hand.B <= kMaxLoopValue)) return bad("hand.B must lie in [0, 1e12] (SI)");
  if (!(hand.K >= 0.0 && hand.K <= kMaxLoopValue)) return bad("hand.K must lie in [0, 1e12] (SI)");
  return true;
}

}  // namespace zwidth::stability
