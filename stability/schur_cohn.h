// Schur-Cohn test: are all roots of a real polynomial strictly inside the unit
// circle? O(n^2), no root finding. Used to verify every K_CR the D-decomposition
// finds, and to decide stability at K -> 0+.
#pragma once

#include <vector>

namespace zwidth::stability {

// coeffs[i] multiplies z^i; the leading coefficient coeffs.back() must be
// non-zero. Returns true when every root has |z| < 1. Schur transform:
// a has all roots inside iff |a_0| < |a_n| and (a_n a(z) - a_0 a*(z))/z does,
// with a*(z) = z^n a(1/z).
bool AllRootsInsideUnitCircle(std::vector<double> coeffs);

}  // namespace zwidth::stability
