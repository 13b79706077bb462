// The nonlinear device (issue 32): time beside error, on fixed seeded inputs.
#include <algorithm>
#include <cmath>

#include <benchmark/benchmark.h>

#include "model/nonlinear_simulate.h"
#include "stability/friction_prediction.h"
#include "stability/wall_simulation.h"
#include "stability/zwidth.h"
#include "tests/karnopp_reference.h"
#include "tests/stick_slip_reference.h"

namespace zwidth {
namespace {

// Table I, 30 s at 1 kHz, 0.03 N m rms (the simulate defaults, seed 1),
// Coulomb 8 mN m, breakaway 10 mN m. Errors: the largest position difference
// over the first 3 s, relative to the range there, against the Karnopp
// reference at T/300 (tests/karnopp_reference.h, O(h): its own error is
// ~5e-6) and against the brute force at T/1000 (tests/stick_slip_reference.h,
// RK4 with the switches bisected: good to ~1e-12).
void BM_StickSlipLog30s(benchmark::State& state) {
  model::SimulateOptions o;
  o.encoder_step_rad = 0.0;
  const model::Friction f{0.008, 0.008, 0.0, 0.01, 0.01};
  model::SimulatedLog log;
  for (auto _ : state) {
    log = model::SimulateNonlinearLog(model::PhantomTable1(), o, f, {});
    benchmark::DoNotOptimize(log.position.data());
  }
  const std::vector<double> u(log.torque.begin(), log.torque.begin() + 3000);
  const std::vector<double> ref = model::KarnoppReference(model::PhantomTable1(), f, u, 1e-3, 300);
  const std::vector<double> brute =
      testing::StickSlipReferenceLog(model::ContinuousStateSpace(model::PhantomTable1()), f, u, 1e-3, 1000);
  double err = 0.0, err_brute = 0.0, lo = ref[0], hi = ref[0];
  for (size_t k = 0; k < ref.size(); ++k) {
    err = std::max(err, std::abs(ref[k] - log.position[k]));
    err_brute = std::max(err_brute, std::abs(brute[k] - log.position[k]));
    lo = std::min(lo, ref[k]);
    hi = std::max(hi, ref[k]);
  }
  state.counters["err_vs_karnopp_T/300"] = err / (hi - lo);
  state.counters["err_vs_brute_force"] = err_brute / (hi - lo);
}
BENCHMARK(BM_StickSlipLog30s)->Unit(benchmark::kMillisecond);

// 10 s of the wall at 1.3 K_cr(0), d = 2, Coulomb 5 mN m, 40960-count encoder,
// from 0.02 rad (inside A*: decays). Counter: the outcome (1 = decays as predicted).
void BM_WallSimulation(benchmark::State& state) {
  const model::Plant p = state.range(0) ? model::PhantomTable1() : model::Plant{1.168e-3, 5.84e-3, {}, 0, "rigid"};
  stability::WallOptions o;
  o.delay_samples = 2;
  o.stiffness = 1.3 * stability::ZWidth(p, 1e-3, 2).At(0.0).K_cr;
  o.friction = model::Friction::Symmetric(0.005);
  o.encoder_step = 2.0 * 3.14159265358979323846 / 40960.0;
  o.initial_position = 0.02;
  stability::WallResult r;
  for (auto _ : state) {
    r = stability::SimulateWall(p, o);
    benchmark::DoNotOptimize(r.position.data());
  }
  state.counters["decays"] = r.outcome == stability::WallOutcome::kDecays;
}
BENCHMARK(BM_WallSimulation)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// A* of Table I at d = 2, B = 0, K = 1.3 K_cr, Coulomb 5 mN m; the bisection's
// tolerance swept. Counter: A* relative to the tightest tolerance's.
void BM_FrictionPrediction(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  const double K = 1.3 * stability::ZWidth(p, 1e-3, 2).At(0.0).K_cr;
  const model::Friction f = model::Friction::Symmetric(0.005);
  stability::FrictionPredictionOptions o;
  o.relative_tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  const double best = stability::PredictFriction(p, 1e-3, 2, {}, K, 0.0, f, 0.0, {}).amplitude;
  double a = 0.0;
  for (auto _ : state) {
    a = stability::PredictFriction(p, 1e-3, 2, {}, K, 0.0, f, 0.0, o).amplitude;
    benchmark::DoNotOptimize(a);
  }
  state.counters["rel_err_A*"] = std::abs(a / best - 1.0);
}
BENCHMARK(BM_FrictionPrediction)->Arg(3)->Arg(6)->Arg(9)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace zwidth
