// Order selection of the fit (fit/order.cc, FitOptions::auto_modes): the true
// number of modes of simulated devices (tests/fit_devices.h), seeded.
#include <string>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "tests/fit_devices.h"

namespace zwidth::fit {
namespace {

class AutoOrder : public ::testing::TestWithParam<int> {};

TEST_P(AutoOrder, PicksTheTrueNumberOfModes) {
  const int n = GetParam();
  for (uint64_t seed : {11u, 12u}) {
    FitOptions o;
    o.auto_modes = true;
    const FitResult r = FitModel(Frf(Device(kPoles[n]), seed), o);
    ASSERT_EQ(r.status, FitStatus::kConverged);
    std::string table;
    for (const OrderTrial& t : r.order_table) {
      table += "\n" + std::to_string(t.num_modes) + " chi2/dof " + std::to_string(t.chi2_per_dof) + " BIC " +
               std::to_string(t.bic) + " poles";
      for (double f : t.pole_hz) table += " " + std::to_string(f);
      for (const std::string& x : t.spurious) table += "; " + x;
    }
    EXPECT_EQ(static_cast<int>(r.plant.modes.size()), n) << r.order_choice << table;
    EXPECT_EQ(r.order_table.size(), 5u);  // 0..max_modes = 4
    EXPECT_EQ(r.quality, FitQuality::kGood) << (r.reasons.empty() ? "" : r.reasons[0].message);
    for (size_t i = 0; i < r.plant.modes.size(); ++i) {
      EXPECT_NEAR(r.plant.modes[i].omega / (kHz * kPoles[n][i]), 1.0, 0.02);
    }
  }
}
INSTANTIATE_TEST_SUITE_P(Fit, AutoOrder, ::testing::Values(0, 1, 2, 3),
                         [](const auto& info) { return std::to_string(info.param) + "Modes"; });

}  // namespace
}  // namespace zwidth::fit
