// The friction fit (fit/friction_fit.h) on logs of tests/friction_sim.h: an
// independent stick-slip simulator of eq. (1) devices with a quantised encoder.
#include "fit/friction_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "model/plant.h"
#include "tests/friction_sim.h"

namespace zwidth::fit {
namespace {

// Table I's PHANToM with the b = 0.004.
model::Plant Phantom() {
  model::Plant p = model::PhantomTable1();
  p.b = 0.004;
  p.delay_samples = 1;
  return p;
}

FitOptions LinearOptions() {
  FitOptions o;
  o.num_modes = 2;
  o.delay_samples = 1;
  return o;
}

TEST(FrictionFit, Explore) {
  const model::Plant p = Phantom();
  for (double frac : {0.0, 0.02, 0.16, 0.30}) {
    for (int counts : {4000, 40960}) {
      testing::FrictionLogOptions so;
      so.coulomb = frac * so.torque_rms;
      so.counts_per_rev = counts;
      so.seed = 7;
      const testing::FrictionLog log = testing::SimulateFrictionLog(p, so);
      const ident::FrequencyResponse frf = ident::EstimateFrequencyResponse(log.torque, log.position, 1000.0, {});
      const FitResult lin = FitModel(frf, LinearOptions());
      FrictionFitOptions fo;
      fo.model = FrictionModel::kCoulomb;
      if (const char* e = std::getenv("FF_IT")) fo.iterations = std::atoi(e);
      if (const char* e = std::getenv("FF_MS")) fo.min_speed_fraction = std::atof(e);
      if (const char* e = std::getenv("FF_FC")) fo.cutoff_hz = std::atof(e);
      const FrictionFitResult r = FitFriction(log.torque, log.position, 1000.0, lin, LinearOptions(), fo);
      std::printf("Fc %.3f counts %d moving %.2f | lin b %.4g (%s) | det %.4g+-%.2g | Fc %.4g+-%.2g off %.3g | idim b %.4g+-%.2g | refit b %.4g+-%.2g m %.4g (%s) cut %.1f rows %d\n",
                  so.coulomb, counts, log.moving_fraction, lin.plant.b, ToString(lin.quality).c_str(), r.detection_coulomb,
                  r.detection_coulomb_std, r.friction.coulomb_pos, r.friction_std.coulomb_pos, r.friction.offset, r.idim_b, r.idim_b_std,
                  r.fit.plant.b, r.fit.std_errors.b, r.fit.plant.m, ToString(r.fit.quality).c_str(), r.cutoff_hz, r.rows_used);
    }
  }
}

}  // namespace
}  // namespace zwidth::fit
