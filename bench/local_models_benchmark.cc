// The frequency-response estimators side by side (issue 23): Welch H1 (Hann
// 4096, 50 %), the LPM and the LRM (ident/local_models.h, default options) on
// a 30 s and a 300 s log at 1 kHz of the Table I plant (model::SimulateLog,
// white torque, PHANToM encoder quantisation, seed 1). Beside the time: the
// median over 0.7-300 Hz and the median over 0.7-5 Hz (where m and b are
// set) of |H - G| / |G| against the exact ZOH response.
#include <algorithm>
#include <complex>
#include <numbers>
#include <vector>

#include <benchmark/benchmark.h>

#include "ident/local_models.h"
#include "ident/welch.h"
#include "model/simulate.h"
#include "model/state_space.h"

namespace {

using namespace zwidth;

const model::SimulatedLog& Log(int seconds) {
  static const model::SimulatedLog logs[2] = {
      [] { model::SimulateOptions o; o.seconds = 30; o.bandwidth_hz = 500; return model::SimulateLog(model::PhantomTable1(), o); }(),
      [] { model::SimulateOptions o; o.seconds = 300; o.bandwidth_hz = 500; return model::SimulateLog(model::PhantomTable1(), o); }()};
  return logs[seconds == 30 ? 0 : 1];
}

double MedianError(const ident::FrequencyResponse& r, double f_lo, double f_hi) {
  const model::DiscreteResponse exact(model::DiscretizeZoh(model::PhantomTable1(), 1e-3));
  std::vector<double> e;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] < f_lo || r.f_hz[k] > f_hi) continue;
    const std::complex<double> g = exact.AtTheta(2.0 * std::numbers::pi * r.f_hz[k] / 1000.0);
    e.push_back(std::abs(r.H[k] - g) / std::abs(g));
  }
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  return e[e.size() / 2];
}

// Arg 0: seconds; arg 1: 0 = h1, 1 = lpm, 2 = lrm.
void BM_Estimator(benchmark::State& state) {
  const model::SimulatedLog& log = Log(static_cast<int>(state.range(0)));
  const int which = static_cast<int>(state.range(1));
  ident::FrequencyResponse r;
  for (auto _ : state) {
    if (which == 0) {
      r = ident::EstimateFrequencyResponse(log.torque, log.position, 1000.0, ident::WelchOptions{});
    } else {
      ident::LocalModelOptions o;
      o.method = which == 1 ? ident::LocalMethod::kPolynomial : ident::LocalMethod::kRational;
      r = ident::EstimateLocal({{log.torque, log.position, {}}}, 1000.0, o).frf;
    }
    benchmark::DoNotOptimize(r.H.data());
  }
  state.SetLabel(which == 0 ? "h1" : which == 1 ? "lpm" : "lrm");
  state.counters["median_rel_err"] = MedianError(r, 0.7, 300.0);
  state.counters["median_rel_err_below_5hz"] = MedianError(r, 0.7, 5.0);
  state.counters["bins"] = static_cast<double>(r.f_hz.size());
}
BENCHMARK(BM_Estimator)->ArgsProduct({{30, 300}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
