// The friction fit (fit/friction_fit.h) on a 30 s log of tests/friction_sim.h
// (Table I's PHANToM, b = 0.004, 1-sample delay, white torque 0.05 N m rms,
// F_c = 8 mN m (16 % of the rms), 4000- and 40960-count encoders, seeded):
// the time of FitFriction after the linear fit, with the relative error of b
// and F_c beside it.
#include <benchmark/benchmark.h>

#include <cmath>

#include "fit/friction_fit.h"
#include "tests/friction_sim.h"

namespace {

using namespace zwidth;

void BM_FrictionFit30s(benchmark::State& state) {
  const model::Plant truth = testing::IssueThirtyTwoDevice();
  testing::FrictionLogOptions so;
  so.coulomb = 0.008;
  so.counts_per_rev = static_cast<int>(state.range(0));
  so.seed = 32;
  const testing::FrictionLog log = testing::SimulateFrictionLog(truth, so);
  fit::FitOptions fo;
  fo.delay_samples = 1;
  const fit::FitResult lin = fit::FitModel(ident::EstimateFrequencyResponse(log.torque, log.position, 1000.0, {}), fo);
  fit::FrictionFitResult r;
  for (auto _ : state) {
    r = fit::FitFriction(log.torque, log.position, 1000.0, lin, fo, fit::FrictionFitOptions{});
    benchmark::ClobberMemory();  // (DoNotOptimize on a double member clobbered it here)
  }
  state.counters["b_rel_err"] = std::abs(r.fit.plant.b / truth.b - 1);
  state.counters["fc_rel_err"] = std::abs(r.friction.coulomb_pos / so.coulomb - 1);
  state.counters["linear_b_rel_err"] = std::abs(lin.plant.b / truth.b - 1);
}
BENCHMARK(BM_FrictionFit30s)->Arg(4000)->Arg(40960)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
