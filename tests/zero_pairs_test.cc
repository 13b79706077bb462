// The zero pairs belong to their sections (issue 23): eq. (1) is unchanged
// when two zero pairs swap sections, so a fit can converge to either
// labelling; fit::FitModel reports the canonical one (pole pairs by omega,
// zero pairs by v, fit::CanonicalOrder) and permutes the covariance with it.
// Response: Welch H1 of a 30 s Table I log (model::SimulateLog, seed 5).
#include <cmath>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "ident/welch.h"
#include "model/simulate.h"

namespace zwidth {
namespace {

// A fit started from the true plant and one started with the two zero pairs
// exchanged end with the same sections, the same std and the same covariance
// entry by entry.
TEST(ZeroPairs, AFitStartedSwappedEndsLabelledAsOneStartedRight) {
  const model::Plant truth = model::PhantomTable1();
  model::SimulateOptions so;
  so.seed = 5;
  const model::SimulatedLog log = model::SimulateLog(truth, so);
  const ident::FrequencyResponse frf =
      ident::EstimateFrequencyResponse(log.torque, log.position, 1000.0, ident::WelchOptions{});
  model::Plant swapped = truth;
  std::swap(swapped.modes[0].v, swapped.modes[1].v);
  std::swap(swapped.modes[0].d, swapped.modes[1].d);
  fit::FitOptions o;
  o.max_starts = 1;
  o.init = truth;
  const fit::FitResult right = fit::FitModel(frf, o);
  o.init = swapped;
  const fit::FitResult other = fit::FitModel(frf, o);
  ASSERT_EQ(right.status, fit::FitStatus::kConverged);
  ASSERT_EQ(other.status, fit::FitStatus::kConverged);
  for (int i = 0; i < 2; ++i) {
    // Section i keeps its own zero: v_1 < w_1 < v_2 < w_2 as in Table I.
    EXPECT_NEAR(right.plant.modes[i].v / truth.modes[i].v, 1.0, 0.01);
    EXPECT_NEAR(other.plant.modes[i].v / right.plant.modes[i].v, 1.0, 1e-5);
    EXPECT_NEAR(other.plant.modes[i].d / right.plant.modes[i].d, 1.0, 1e-3);
    EXPECT_NEAR(other.std_errors.modes[i].d / right.std_errors.modes[i].d, 1.0, 1e-2);
  }
  ASSERT_EQ(right.log_covariance.size(), other.log_covariance.size());
  ASSERT_FALSE(right.log_covariance.empty());
  const size_t p = static_cast<size_t>(std::lround(std::sqrt(right.log_covariance.size())));
  const std::vector<double>& C = right.log_covariance;
  for (size_t i = 0; i < p; ++i) {
    for (size_t j = 0; j < p; ++j) {  // within 1 % of the correlation scale sqrt(C_ii C_jj)
      EXPECT_NEAR(other.log_covariance[i * p + j], C[i * p + j], 1e-2 * std::sqrt(C[i * p + i] * C[j * p + j]))
          << i << "," << j;
    }
  }
}

}  // namespace
}  // namespace zwidth
