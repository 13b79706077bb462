// The fit of eq. (1) to the local methods' responses (ident/local_models.h):
// accuracy and honesty of the std over seeds (Monte Carlo), the stress label's
// 16-seed sweep and the unit label's smaller check.
//
// The sweep and its logs: tests/local_fit_sweep.h.
#include <gtest/gtest.h>

#include "tests/local_fit_sweep.h"

namespace zwidth {
namespace {

// The unit label's check: 4 seeds of Table I by the LRM. The errors of m and
// b stay within the bounds of the 16-seed sweep (0.01 %, 0.05 %), and the
// reported std is within a factor 3 of the rms error (4 seeds cannot say more).
TEST(LocalFit, FourTable1LogsGiveMAndBWithinTheirStd) {
  const Sweep w = MonteCarlo(model::PhantomTable1(), "lrm", 4);
  EXPECT_LT(w.rms_m, 1e-4);
  EXPECT_LT(w.rms_b, 5e-4);
  EXPECT_GT(w.std_m / w.rms_m, 1.0 / 3.0);
  EXPECT_LT(w.std_m / w.rms_m, 3.0);
}

}  // namespace
}  // namespace zwidth
