#include "stability/schur_cohn.h"

#include <cmath>

namespace zwidth::stability {

bool AllRootsInsideUnitCircle(std::vector<double> a) {
  while (a.size() > 1 && a.back() == 0.0) a.pop_back();
  std::vector<double> next;
  while (a.size() > 1) {
    const size_t n = a.size() - 1;
    const double an = a[n], a0 = a[0];
    if (!(std::abs(a0) < std::abs(an))) return false;
    // b(z) = (an a(z) - a0 a*(z)) / z, degree n - 1; normalise to avoid
    // overflow/underflow over many steps.
    next.assign(n, 0.0);
    double scale = 0.0;
    for (size_t i = 1; i <= n; ++i) {
      next[i - 1] = an * a[i] - a0 * a[n - i];
      scale = std::max(scale, std::abs(next[i - 1]));
    }
    if (!(scale > 0.0) || !std::isfinite(scale)) return false;
    for (double& v : next) v /= scale;
    a.swap(next);
  }
  return true;
}

}  // namespace zwidth::stability
