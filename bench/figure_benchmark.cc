// Thinning a figure's lines (report/polyline.h) before gnuplot reads them: time
// against the error it allows. Input (fixed, seeded): the Bode lines of `zwidth
// run` on a 4096-sample Welch grid at 1 kHz (2049 bins, log frequency across
// 900 px): Table I's exact ZOH magnitude (log axis) and phase (linear), and the
// same with 1 % multiplicative noise (seed 1) as a measured response. Arg: the
// tolerance [1/100 px]. Counters: kept rows, and max_dev_px, the largest
// distance of a dropped row from the kept polyline over both series, measured
// here by brute force (every dropped row against the segment of its kept
// neighbours).
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "model/plant.h"
#include "model/state_space.h"
#include "report/polyline.h"

namespace zwidth {
namespace {

struct BodeLines {
  std::vector<double> f_hz, mag, phase_deg;
};

BodeLines MakeBode(bool noisy) {
  const model::DiscreteResponse g(model::DiscretizeZoh(model::PhantomTable1(), 1e-3));
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 0.01);
  BodeLines b;
  double prev = 0.0;
  for (int k = 1; k < 2049; ++k) {
    const double f = k * 1000.0 / 4096;
    std::complex<double> h = g.AtTheta(2 * std::numbers::pi * f * 1e-3);
    if (noisy) h *= std::complex<double>(1 + n(rng), n(rng));
    double ph = std::arg(h) * 180 / std::numbers::pi;
    if (k > 1) ph += 360.0 * std::round((prev - ph) / 360.0);
    prev = ph;
    b.f_hz.push_back(f);
    b.mag.push_back(std::abs(h));
    b.phase_deg.push_back(ph);
  }
  return b;
}

double MaxDeviationPx(const BodeLines& b, const std::vector<report::DrawnSeries>& s, const report::PixelAxis& fx,
                      const std::vector<size_t>& kept) {
  double worst = 0.0;
  for (size_t j = 0; j + 1 < kept.size(); ++j) {
    for (size_t i = kept[j] + 1; i < kept[j + 1]; ++i) {
      for (const report::DrawnSeries& d : s) {
        const auto& y = *d.y;
        worst = std::max(worst, report::DistanceToSegment(
                                    fx.ToPixel(b.f_hz[i]), d.y_axis.ToPixel(y[i]), fx.ToPixel(b.f_hz[kept[j]]),
                                    d.y_axis.ToPixel(y[kept[j]]), fx.ToPixel(b.f_hz[kept[j + 1]]),
                                    d.y_axis.ToPixel(y[kept[j + 1]])));
      }
    }
  }
  return worst;
}

void BM_ThinBodeLines(benchmark::State& state) {
  const bool noisy = state.range(1) != 0;
  static const BodeLines model = MakeBode(false), measured = MakeBode(true);
  const BodeLines& b = noisy ? measured : model;
  const double tol = state.range(0) / 100.0;
  const report::PixelAxis fx = report::AxisSpanning(b.f_hz, 900, true);
  const std::vector<report::DrawnSeries> s = {{&b.mag, report::AxisSpanning(b.mag, 640, true)},
                                              {&b.phase_deg, report::AxisSpanning(b.phase_deg, 640, false)}};
  std::vector<size_t> kept;
  for (auto _ : state) {
    kept = report::ThinPolylines(b.f_hz, fx, s, tol);
    benchmark::DoNotOptimize(kept.data());
  }
  state.counters["rows"] = static_cast<double>(b.f_hz.size());
  state.counters["kept"] = static_cast<double>(kept.size());
  state.counters["max_dev_px"] = MaxDeviationPx(b, s, fx, kept);
}
BENCHMARK(BM_ThinBodeLines)->ArgsProduct({{5, 20, 100}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace zwidth
