// Time against error for each stage, on fixed seeded inputs (Table I, 30 s
// log at 1 kHz, seed 1). Each benchmark reports its error as a counter and
// sweeps the knob that trades one for the other.
#include <cmath>
#include <cstddef>
#include <type_traits>
#include <random>
#include <numbers>

#include <benchmark/benchmark.h>

#include <optional>
#include "analysis/plant_stability.h"
#include "fit/fit.h"
#include "ident/welch.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "model/state_space.h"
#include "stability/cutoff_sweep.h"
#include "stability/hand.h"
#include "stability/loop_options.h"
#include "stability/passivity.h"
#include "stability/relay.h"
#include "stability/velocity_filter.h"
#include "tests/brute_force.h"
#include "tests/brute_force_wide.h"
#include "tests/devices.h"
#include <unsupported/Eigen/MatrixFunctions>
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth {
namespace {

const model::SimulatedLog& Log() {
  static const model::SimulatedLog log = [] { model::SimulateOptions o; o.seed = 1; return model::SimulateLog(model::PhantomTable1(), o); }();
  return log;
}

// 95th-percentile relative error against the exact sampled response over bins
// with coherence > 0.99.
double ResponseError(const ident::FrequencyResponse& r) {
  const model::DiscreteResponse g(model::DiscretizeZoh(model::PhantomTable1(), 1e-3));
  std::vector<double> e;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.coherence[k] < 0.99) continue;
    const auto t = g.AtTheta(2 * std::numbers::pi * r.f_hz[k] / 1000);
    e.push_back(std::abs(r.H[k] - t) / std::abs(t));
  }
  std::sort(e.begin(), e.end());
  return e.empty() ? NAN : e[e.size() * 95 / 100];
}

void BM_Estimate(benchmark::State& state) {
  ident::WelchOptions o;
  o.window_length = static_cast<int>(state.range(0));
  o.overlap = state.range(1) / 100.0;
  ident::FrequencyResponse r;
  for (auto _ : state) {
    r = ident::EstimateFrequencyResponse(Log().torque, Log().position, 1000, o);
    benchmark::DoNotOptimize(r.H.data());
  }
  state.counters["p95_rel_err"] = ResponseError(r);
  state.counters["averages"] = r.num_averages;
}
BENCHMARK(BM_Estimate)->ArgsProduct({{1024, 2048, 4096}, {0, 50, 75}})->Unit(benchmark::kMicrosecond);

// An hour at 1 kHz (3.6 M samples), streamed through the estimator in 64 k
// chunks as the log readers deliver it.
void BM_EstimateHour(benchmark::State& state) {
  static const model::SimulatedLog hour = [] {
    model::SimulateOptions o;
    o.seconds = 3600;
    return model::SimulateLog(model::PhantomTable1(), o);
  }();
  ident::FrequencyResponse r;
  for (auto _ : state) {
    ident::WelchEstimator est(ident::WelchOptions{});
    for (size_t s = 0; s < hour.torque.size(); s += 65536) {
      est.Push(hour.torque.data() + s, hour.position.data() + s, std::min<size_t>(65536, hour.torque.size() - s));
    }
    r = est.Finish(1000);
  }
  state.counters["p95_rel_err"] = ResponseError(r);
  state.counters["averages"] = r.num_averages;
}
BENCHMARK(BM_EstimateHour)->Unit(benchmark::kMillisecond);

double MaxParamError(const model::Plant& a, const model::Plant& b) {
  double e = std::max(std::abs(a.m / b.m - 1), std::abs(a.b / b.b - 1));
  for (size_t i = 0; i < a.modes.size(); ++i) {
    e = std::max({e, std::abs(a.modes[i].omega / b.modes[i].omega - 1), std::abs(a.modes[i].v / b.modes[i].v - 1)});
  }
  return e;
}

void BM_Fit(benchmark::State& state) {
  const ident::FrequencyResponse r =
      ident::EstimateFrequencyResponse(Log().torque, Log().position, 1000, ident::WelchOptions{});
  fit::FitOptions o;
  o.max_starts = static_cast<int>(state.range(0));
  o.function_tolerance = std::pow(10.0, -static_cast<double>(state.range(1)));
  fit::FitResult res;
  for (auto _ : state) res = fit::FitModel(r, o);
  state.counters["max_rel_err_m_b_freqs"] = MaxParamError(res.plant, model::PhantomTable1());
  state.counters["chi2_per_dof"] = res.chi2_per_dof;
  state.counters["converged"] = res.status == fit::FitStatus::kConverged;
}
BENCHMARK(BM_Fit)->ArgsProduct({{1, 3, 6}, {6, 8, 10}})->Unit(benchmark::kMillisecond);

// --modes auto (0..4 sections, BIC) on the shipped log (datasets/phantom/
// phantom_30s.h5 is this same simulation: Table I, seed 1, defaults); range(0)
// = 1 adds --delay-samples auto. The chosen order and the parameter error are
// reported beside the time (error NaN when the order is not Table I's 2).
void BM_FitAutoModes(benchmark::State& state) {
  const ident::FrequencyResponse r =
      ident::EstimateFrequencyResponse(Log().torque, Log().position, 1000, ident::WelchOptions{});
  fit::FitOptions o;
  o.auto_modes = true;
  o.auto_delay = state.range(0) != 0;
  fit::FitResult res;
  for (auto _ : state) res = fit::FitModel(r, o);
  state.counters["chosen_modes"] = static_cast<double>(res.plant.modes.size());
  state.counters["chosen_delay"] = res.plant.delay_samples;
  state.counters["max_rel_err_m_b_freqs"] =
      res.plant.modes.size() == 2 ? MaxParamError(res.plant, model::PhantomTable1()) : NAN;
  state.counters["good"] = res.quality == fit::FitQuality::kGood;
}
BENCHMARK(BM_FitAutoModes)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Fixed order (2 sections) on Table I simulated with an input delay of 7
// samples (SimulateLog, seed 3, otherwise defaults): range(0) = 0 gives the
// delay, 1 searches it (--delay-samples auto). The delay found and the
// parameter error are reported beside the time.
void BM_FitDelaySearch(benchmark::State& state) {
  static const ident::FrequencyResponse r = [] {
    model::SimulateOptions so;
    so.seed = 3;
    so.delay_samples = 7;
    const model::SimulatedLog log = model::SimulateLog(model::PhantomTable1(), so);
    return ident::EstimateFrequencyResponse(log.torque, log.position, 1000, ident::WelchOptions{});
  }();
  fit::FitOptions o;
  o.delay_samples = 7;
  o.auto_delay = state.range(0) != 0;
  fit::FitResult res;
  for (auto _ : state) res = fit::FitModel(r, o);
  state.counters["chosen_delay"] = res.plant.delay_samples;
  state.counters["max_rel_err_m_b_freqs"] = MaxParamError(res.plant, model::PhantomTable1());
  state.counters["good"] = res.quality == fit::FitQuality::kGood;
}
BENCHMARK(BM_FitDelaySearch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// 100-point sweep at d = 2 (construction included), error against a reference
// computed with a 16x finer grid and verification.
void BM_BoundarySweep(benchmark::State& state) {
  stability::BoundaryOptions o;
  o.min_grid_points = static_cast<int>(state.range(0));
  o.verify = state.range(1) != 0;
  stability::BoundaryOptions ref_o;
  ref_o.min_grid_points = 32768;
  const stability::ZWidth ref(model::PhantomTable1(), 1e-3, 2, ref_o);
  double err = 0;
  for (auto _ : state) {
    const stability::ZWidth z(model::PhantomTable1(), 1e-3, 2, o);
    for (int i = 0; i < 100; ++i) benchmark::DoNotOptimize(z.At(0.001 * i).K_cr);
  }
  const stability::ZWidth z(model::PhantomTable1(), 1e-3, 2, o);
  for (int i = 0; i < 100; ++i) {
    const double a = z.At(0.001 * i).K_cr, b = ref.At(0.001 * i).K_cr;
    if (b > 0) err = std::max(err, std::abs(a / b - 1));
  }
  state.counters["max_rel_err_K_cr"] = err;
}
BENCHMARK(BM_BoundarySweep)->ArgsProduct({{256, 2048}, {0, 1}})->Unit(benchmark::kMillisecond);

// The 8010-point map: d = 1..10, B = 0:0.0005:0.4, on one sampled plant
// (stability/sampled_plant.h) shared by the delays, sampling included. Error:
// the largest relative difference of K_CR from the brute force's
// (tests/brute_force.h: companion-matrix eigenvalues, geometric scan and
// bisection) at every 100th B of every delay (90 points).
void BM_BoundaryMap(benchmark::State& state) {
  for (auto _ : state) {
    const stability::SampledPlant sp(model::PhantomTable1(), 1e-3);
    for (int d = 1; d <= 10; ++d) {
      const stability::ZWidth z(sp, d);
      for (int i = 0; i <= 800; ++i) benchmark::DoNotOptimize(z.At(0.0005 * i).K_cr);
    }
  }
  double err = 0;
  for (int d = 1; d <= 10; ++d) {
    const stability::ZWidth z(model::PhantomTable1(), 1e-3, d);
    const stability::BruteForce bf(model::PhantomTable1(), 1e-3, d);
    for (int i = 0; i <= 800; i += 100) {
      const double a = z.At(0.0005 * i).K_cr, b = bf.KCritical(0.0005 * i);
      if (b > 0 && std::isfinite(b)) err = std::max(err, std::abs(a / b - 1));
      else if (a != b) err = std::max(err, 1.0);  // 0 or inf on one side only
    }
  }
  state.counters["max_rel_err_K_cr_vs_brute_force"] = err;
}
BENCHMARK(BM_BoundaryMap)->Unit(benchmark::kMillisecond);

// Stable K intervals on a 1000-point B grid at one delay (construction
// included): Table I at d = 2 (arg 0) and the issue's reopened-band device at
// d = 4 (arg 1), B from 0 to 1.05 B_max. Error: the largest relative
// difference of any interval end from a reference with a 16x finer theta grid.
void BM_StableIntervals(benchmark::State& state) {
  const model::Plant p = state.range(0) == 0 ? model::PhantomTable1() : test::IssueDeviceOne();
  const int d = state.range(0) == 0 ? 2 : 4;
  const double b_max = stability::ZWidth(p, 1e-3, d).Summarize().B_max;
  std::vector<double> grid(1000);
  for (int i = 0; i < 1000; ++i) grid[i] = 1.05 * b_max * i / 999.0;
  for (auto _ : state) {
    const stability::ZWidth z(p, 1e-3, d);
    for (double B : grid) benchmark::DoNotOptimize(z.StableIntervals(B).size());
  }
  stability::BoundaryOptions ref_o;
  ref_o.min_grid_points = 32768;
  const stability::ZWidth ref(p, 1e-3, d, ref_o), z(p, 1e-3, d);
  double err = 0;
  int mismatched = 0;
  for (double B : grid) {
    const auto a = z.StableIntervals(B), b = ref.StableIntervals(B);
    if (a.size() != b.size()) { ++mismatched; continue; }
    for (size_t k = 0; k < a.size(); ++k) {
      if (b[k].K_lo > 0) err = std::max(err, std::abs(a[k].K_lo / b[k].K_lo - 1));
      if (std::isfinite(b[k].K_hi)) err = std::max(err, std::abs(a[k].K_hi / b[k].K_hi - 1));
    }
  }
  state.counters["max_rel_err_ends"] = err;
  state.counters["interval_count_mismatches"] = mismatched;
}
BENCHMARK(BM_StableIntervals)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The brute force's boundary near an interval end k at B: 60 bisections of
// its closed-loop eigenvalues on [k (1 - span), k (1 + span)].
double BisectEnd(const stability::LoopBruteForce& bf, double k, double B, double span) {
  double lo = (1 - span) * k, hi = (1 + span) * k;
  const bool s_lo = bf.MaxRoot(lo, B) < 1;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    ((bf.MaxRoot(mid, B) < 1) == s_lo ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Issue 16: the stable intervals on a 1000-point B grid (0 to 1.05 B_max) of
// Table I at d = 4 with a 50 Hz velocity low-pass and a hand (M = 0.3 m,
// B = b, K giving 2 Hz), construction included; error: every finite interval
// end of 100 of the B values against a bisection (60 steps) of the brute
// force's eigenvalues (tests/brute_force.h, the closed loop as one matrix).
void BM_LoopBoundary(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  stability::LoopOptions l;
  stability::SetLowPassFilter(50.0, 1e-3, &l);
  const double w = 2 * std::numbers::pi * 2.0;
  l.hand = {0.3 * p.m, p.b, w * w * 1.3 * p.m};
  const int d = 4;
  const double b_max = stability::ZWidth(p, 1e-3, d, l).Summarize().B_max;
  std::vector<double> grid(1000);
  for (int i = 0; i < 1000; ++i) grid[i] = 1.05 * b_max * i / 999.0;
  for (auto _ : state) {
    const stability::ZWidth z(p, 1e-3, d, l);
    for (double B : grid) benchmark::DoNotOptimize(z.StableIntervals(B).size());
  }
  const model::StateSpace c = stability::ContinuousStateSpaceWithHand(p, l.hand);
  const int n = static_cast<int>(c.A.rows());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 1, n + 1);
  M.topLeftCorner(n, n) = c.A * 1e-3;
  M.topRightCorner(n, 1) = c.B * 1e-3;
  const Eigen::MatrixXd E = M.exp();
  const stability::LoopBruteForce bf(E.topLeftCorner(n, n), E.topRightCorner(n, 1), c.C, l.filter_b, l.filter_a,
                                     d + p.delay_samples, 1e-3);
  const stability::ZWidth z(p, 1e-3, d, l);
  double err = 0;
  int ends = 0;
  for (int i = 0; i < 1000; i += 10) {
    for (const auto& iv : z.StableIntervals(grid[i])) {
      for (double k : {iv.K_lo, iv.K_hi}) {
        if (!(k > 0 && std::isfinite(k))) continue;
        err = std::max(err, std::abs(BisectEnd(bf, k, grid[i], 0.1) / k - 1));
        ++ends;
      }
    }
  }
  state.counters["max_rel_err_vs_brute_force"] = err;
  state.counters["ends_checked"] = ends;
}
BENCHMARK(BM_LoopBoundary)->Unit(benchmark::kMillisecond);

// The cut-off sweep: 20 log-spaced cut-offs 5-250 Hz, K_CR^max, Table I at
// d = 2; error: K_CR(0) of the best cut-off against the brute force's bisection.
void BM_CutoffSweep(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  stability::CutoffSweepOptions o;
  for (int i = 0; i < 20; ++i) o.cutoffs_hz.push_back(5.0 * std::pow(50.0, i / 19.0));
  stability::CutoffSweepResult r;
  for (auto _ : state) {
    r = stability::SweepCutoff(p, 1e-3, 2, stability::LoopOptions{}, o);
    benchmark::DoNotOptimize(r.best);
  }
  stability::LoopOptions l;
  stability::SetLowPassFilter(r.cutoffs_hz[r.best], 1e-3, &l);
  const model::StateSpace dz = model::DiscretizeZoh(p, 1e-3);
  const stability::LoopBruteForce bf(dz.A, dz.B, dz.C, l.filter_b, l.filter_a, 2 + p.delay_samples, 1e-3);
  const double k = stability::ZWidth(p, 1e-3, 2, l).At(0.0).K_cr;
  double lo = 0.9 * k, hi = 1.1 * k;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (bf.MaxRoot(mid, 0.0) < 1 ? lo : hi) = mid;
  }
  state.counters["best_cutoff_hz"] = r.cutoffs_hz[r.best];
  state.counters["best_K_cr_max"] = r.measure[r.best];
  state.counters["rel_err_K_cr0_vs_brute_force"] = std::abs(0.5 * (lo + hi) / k - 1);
}
BENCHMARK(BM_CutoffSweep)->Unit(benchmark::kMillisecond);

// The passive K (Colgate-Schenkel) of the boundary rows (arg 0: At, which
// also finds K_lo; arg 1: KHi, what the rows use): 1000 B values at
// d = 4 with a 50 Hz first-order velocity filter, Table I's b. Error: largest
// difference of K_hi from a brute-force minimum of (b + B R)/P over 2e5 + 1
// uniform theta, relative to K_hi(0) (the brute force's own grid error is of
// order 1e-9).
void BM_PassivityRows(benchmark::State& state) {
  const double T = 1e-3, b = model::PhantomTable1().b;
  stability::LoopOptions loop;
  stability::SetLowPassFilter(50.0, T, &loop);
  const int D = 4;
  const stability::Passivity pa(b, T, D, loop);
  std::vector<double> Bs;
  for (int i = 0; i < 1000; ++i) Bs.push_back(0.06 * i / 999.0);
  std::vector<double> K(Bs.size());
  for (auto _ : state) {
    for (size_t i = 0; i < Bs.size(); ++i) K[i] = state.range(0) == 0 ? pa.At(Bs[i]).K_hi : pa.KHi(Bs[i]);
    benchmark::DoNotOptimize(K.data());
  }
  std::vector<double> best(Bs.size(), INFINITY);
  const int m = 200000;
  for (int k = 0; k <= m; ++k) {
    const double th = std::numbers::pi * k / m;
    const double P = pa.Rhs(1.0, 0.0, th), R = -pa.Rhs(0.0, 1.0, th);
    if (P > 0)
      for (size_t i = 0; i < Bs.size(); ++i) best[i] = std::min(best[i], (b + Bs[i] * R) / P);
  }
  double err = 0;  // relative to K_hi at B = 0
  for (size_t i = 0; i < Bs.size(); ++i)
    if (K[i] > 0) err = std::max(err, std::abs(K[i] - best[i]) / K[0]);
  state.counters["max_err_vs_dense_grid"] = err;
}
BENCHMARK(BM_PassivityRows)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);  // At(B).K_hi, KHi(B)

// The largest relative difference of K[i] = K_CR(0.008 i), i < 8, from a
// 60-step bisection of the brute force's closed-loop eigenvalues; a K_CR of 0
// (past B_max_from_zero) is right when the brute force is unstable just above
// K = 0; 1 for any other non-positive or non-finite K_CR.
// refine(k_bisected, K_CR, B), when given: the reference from the bisection's
// result (BM_CrowdedModeBoundary: its last steps in 30 digits).
template <class BruteForce, class Refine = std::nullptr_t>
double KcrErrorAt8B(const BruteForce& bf, const std::vector<double>& K, const Refine& refine = nullptr) {
  double err = 0;
  for (int i = 0; i < 8; ++i) {
    if (K[i] == 0.0) { if (!(bf.MaxRoot(1e-6 * K[0], 0.008 * i) >= 1.0)) err = 1.0; continue; }
    if (!(K[i] > 0 && std::isfinite(K[i]))) { err = 1.0; continue; }
    double lo = 0.9 * K[i], hi = 1.1 * K[i];
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (bf.MaxRoot(mid, 0.008 * i) < 1 ? lo : hi) = mid;
    }
    double ref = 0.5 * (lo + hi);
    if constexpr (!std::is_same_v<Refine, std::nullptr_t>) ref = refine(ref, K[i], 0.008 * i);
    err = std::max(err, std::abs(ref / K[i] - 1));
  }
  return err;
}

// Issue 31: K_CR(B) of the n-section family of the issue (n = 1, 2, 3, 8, 16,
// 64; omega_i = 300 * 1.08^i rad/s, damping ratio 0.025, v_i = 0.93 omega_i,
// Table I's m and b, T = 1 ms, d = 2), 8 B values from 0 to 0.056,
// construction included; at 8 sections and more the
// eigenvalue test decides (the polynomial's poles move by far more than their
// distance to the circle). Error: the largest relative difference of K_CR
// from a 60-step bisection of the brute force's closed-loop eigenvalues
// (tests/brute_force.h, MakeBrute: its own unbalanced ZOH).
void BM_ManyModeBoundary(benchmark::State& state) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < state.range(0); ++i) {
    const double w = 300.0 * std::pow(1.08, i), v = 0.93 * w;
    p.modes.push_back({w, 0.05 * w, v, 0.05 * v});
  }
  std::vector<double> K(8);
  for (auto _ : state) {
    const stability::ZWidth z(p, 1e-3, 2);
    for (int i = 0; i < 8; ++i) K[i] = z.At(0.008 * i).K_cr;
    benchmark::DoNotOptimize(K.data());
  }
  state.counters["max_rel_err_K_cr_vs_brute_force"] = KcrErrorAt8B(stability::MakeBrute(p, {}, 2, 1e-3), K);
  state.counters["K_cr_at_zero_B"] = K[0];
}
BENCHMARK(BM_ManyModeBoundary)->Arg(1)->Arg(2)->Arg(3)->Arg(8)->Arg(16)->Arg(64)->Unit(benchmark::kMillisecond);

// Issue 31: the same at n crowded, lightly damped sections (n = 8, 16, 32;
// 1 % apart, damping ratio 1e-4, first at 300 rad/s), where the double
// pole-residue sum cancels and the double state space errs near the modes
// (8 sections: 4e-7 against a long double ZOH): G_d in binary128. Error: the
// largest relative difference of K_CR from the brute force's boundary
// (tests/brute_force.h, IndependentZoh: the tests' own realisation and ZOH):
// a 60-step bisection of its long double eigenvalues, whose last steps are
// redone in 30 digits (tests/brute_force_wide.h, WideBisect: 30 steps on
// 1e-5 either side of both K_CR and the long double's boundary), since at 32
// sections long double misplaces the boundary by 1.6e-6 (its error beside:
// long_double_ref_err). Without Boost the long double figure alone
// (wide_referee = 0).
void BM_CrowdedModeBoundary(benchmark::State& state) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < state.range(0); ++i) {
    const double w = 300.0 * std::pow(1.01, i), v = 0.93 * w;
    p.modes.push_back({w, 2e-4 * w, v, 2e-4 * v});
  }
  std::vector<double> K(8);
  for (auto _ : state) {
    const stability::ZWidth z(p, 1e-3, 2);
    for (int i = 0; i < 8; ++i) K[i] = z.At(0.008 * i).K_cr;
    benchmark::DoNotOptimize(K.data());
  }
  const stability::IndependentZoh<long double> zoh(p, 1e-3);
  const stability::LoopBruteForceT<long double> bf(zoh.A, zoh.B, zoh.C, {}, {}, 2, 1e-3);
#if ZWIDTH_HAVE_WIDE_BRUTE_FORCE
  const stability::WideBruteForce wide(p, 2, 1e-3);
  double ld_err = 0.0;
  auto refine = [&](double k_ld, double k_zw, double B) {
    const double mid = 0.5 * (k_ld + k_zw), span = std::abs(k_ld - k_zw) / mid + 1e-5;
    const double k = stability::WideBisect(wide, mid, B, span, 30);
    if (!std::isfinite(k)) return k_ld;  // no boundary near: KcrErrorAt8B's figure stands
    ld_err = std::max(ld_err, std::abs(k_ld / k - 1));
    return k;
  };
  state.counters["max_rel_err_K_cr_vs_brute_force"] = KcrErrorAt8B(bf, K, refine);
  state.counters["long_double_ref_err"] = ld_err;
  state.counters["wide_referee"] = 1;
#else
  state.counters["max_rel_err_K_cr_vs_brute_force"] = KcrErrorAt8B(bf, K);
  state.counters["wide_referee"] = 0;
#endif
  state.counters["K_cr_at_zero_B"] = K[0];
}
BENCHMARK(BM_CrowdedModeBoundary)->Arg(8)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond);

// Issue 31's hardest corner: 64 sections 1 % apart at damping ratio 1e-4
// (omega_i = 300 x 1.01^i rad/s, v_i = 0.93 omega_i, Table I's m and b,
// T = 1 ms) at delay 0, 2, 20 (the arg): construction, Summarize and K_CR at
// 8 B values from 0 to 0.9 B_max_from_zero (the poles' eigenvalue_shift is
// 3.4e-4: UnstableRoots counts the crossings). Error: the largest relative
// difference of K_CR at B = 0, 0.26 and 0.64 B_max_from_zero from a 20-step
// 30-digit bisection over K_CR (1 -+ 1e-5) (tests/brute_force_wide.h; its
// resolution, 1.9e-11, is the smallest error it can show; double and long double cannot resolve the integrator's root 6e-14
// inside the circle at K ~ 1e-13); 1 where the bisection does not straddle a
// boundary. Without Boost no error (wide_referee = 0).
void BM_CornerBoundary(benchmark::State& state) {
  model::Plant p = model::PhantomTable1();
  p.modes.clear();
  for (int i = 0; i < 64; ++i) {
    const double w = 300.0 * std::pow(1.01, i), v = 0.93 * w;
    p.modes.push_back({w, 2e-4 * w, v, 2e-4 * v});
  }
  const int d = static_cast<int>(state.range(0));
  std::vector<double> K(8), Bs(8);
  int verified = 0;
  for (auto _ : state) {
    const stability::ZWidth z(p, 1e-3, d);
    const stability::DelaySummary s = z.Summarize();
    verified = 0;
    for (int i = 0; i < 8; ++i) {
      Bs[i] = 0.9 * s.B_max_from_zero * i / 7.0;
      const stability::CriticalPoint c = z.At(Bs[i]);
      K[i] = c.K_cr;
      verified += c.verified;
    }
    benchmark::DoNotOptimize(K.data());
  }
  state.counters["verified_of_8"] = verified;
  state.counters["K_cr_at_zero_B"] = K[0];
#if ZWIDTH_HAVE_WIDE_BRUTE_FORCE
  const stability::WideBruteForce wide(p, d, 1e-3);
  double err = 0.0;
  for (int i : {0, 2, 5}) {  // B = 0, 0.26, 0.64 B_max_from_zero
    const double k = stability::WideBisect(wide, K[i], Bs[i], 1e-5, 20);
    err = std::max(err, std::isfinite(k) ? std::abs(K[i] / k - 1) : 1.0);
  }
  state.counters["max_rel_err_K_cr_vs_30_digit_brute_force"] = err;
  state.counters["wide_referee"] = 1;
#else
  state.counters["wide_referee"] = 0;
#endif
}
BENCHMARK(BM_CornerBoundary)->Arg(0)->Arg(2)->Arg(20)->Unit(benchmark::kMillisecond)->Iterations(1);

// Long loop delays (Table I, T = 1 ms, d = 100, 170, 240 samples; past ~163
// the characteristic polynomial's boundary error exceeds 1e-9 and the
// closed loop's eigenvalues decide): the summary and the boundary rows of a
// 100-point B grid (0 to 1.05 B_max), construction included, as `boundary
// --delays d --b-points 100` computes them. Error: every finite interval end
// at 10 of the B values against a 60-step bisection of the brute force's
// closed-loop eigenvalues (tests/brute_force.h, IndependentZoh + LoopBruteForce).
void BM_LongDelayBoundary(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  const int d = static_cast<int>(state.range(0));
  std::vector<double> grid(100);
  std::vector<std::vector<stability::KInterval>> rows(grid.size());
  bool eigen = false;
  for (auto _ : state) {
    const stability::ZWidth z(p, 1e-3, d);
    const stability::DelaySummary s = z.Summarize();
    for (size_t i = 0; i < grid.size(); ++i) grid[i] = 1.05 * s.B_max * i / (grid.size() - 1.0);
    for (size_t i = 0; i < grid.size(); ++i) rows[i] = z.RowAt(grid[i]).intervals;
    eigen = !z.uses_polynomial_test();
  }
  const stability::IndependentZoh<double> zoh(p, 1e-3);
  const stability::LoopBruteForce bf(zoh.A, zoh.B, zoh.C, {}, {}, d, 1e-3);
  double err = 0;
  int ends = 0, unverified = 0;
  for (size_t i = 0; i < grid.size(); i += 10) {
    for (const stability::KInterval& iv : rows[i]) {
      unverified += !iv.verified;
      for (double k : {iv.K_lo, iv.K_hi}) {
        if (!(k > 0 && std::isfinite(k))) continue;
        err = std::max(err, std::abs(BisectEnd(bf, k, grid[i], 0.01) / k - 1));
        ++ends;
      }
    }
  }
  state.counters["max_rel_err_ends_vs_brute_force"] = err;
  state.counters["ends_checked"] = ends;
  state.counters["unverified_intervals"] = unverified;
  state.counters["eigenvalue_test"] = eigen;
}
BENCHMARK(BM_LongDelayBoundary)->Arg(100)->Arg(170)->Arg(240)->Unit(benchmark::kMillisecond)->Iterations(1);

// Table I's rigid body with n sections (0-4): its two, then sections at 45
// and 70 Hz (pole 8 % above its zero, zeta 0.1).
model::Plant PlantWithSections(int n) {
  model::Plant p = model::PhantomTable1();
  std::vector<model::Mode> modes = p.modes;
  for (double f : {45.0, 70.0}) {
    const double w = 2 * std::numbers::pi * f * 1.08, v = 2 * std::numbers::pi * f;
    modes.push_back({w, 2 * 0.1 * w, v, 2 * 0.1 * v});
  }
  modes.resize(n);
  p.modes = modes;
  return p;
}
// `zwidth run`'s boundary stage (analysis::AnalysePlantStability): Table I
// (arg: the number of sections, PlantWithSections; 2 = Table I itself)
// with the seeded covariance of BM_DeltaMethodStd, delays 2, 4, 8, 1000 B
// values each: summaries and their std, intervals, K_CR and its std, passive
// K; on the threads of model/parallel.h. Error: largest relative difference
// of K_CR from the brute force's (tests/brute_force.h) on every 50th row.
void BM_RunBoundary(benchmark::State& state) {
  io::ModelFile m;
  m.plant = PlantWithSections(static_cast<int>(state.range(0)));
  const int n = stability::NumLogParameters(m.plant);
  m.log_covariance.assign(n * n, 0.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int i = 0; i < n; ++i) m.log_covariance[i * n + i] = 1e-4 * (1.0 + 0.5 * std::abs(g(rng)));
  const std::vector<int> delays = {2, 4, 8};
  std::optional<analysis::PlantStability> r;
  for (auto _ : state) {
    r.emplace(analysis::AnalysePlantStability(m, 1e-3, {.delays = delays}));
    benchmark::DoNotOptimize(r->rows.data());
  }
  double err = 0;
  const size_t nB = r->b_grid.size();
  for (size_t i = 0; i < delays.size(); ++i) {
    const stability::BruteForce bf(m.plant, 1e-3, delays[i]);
    for (size_t k = 0; k < nB; k += 50) {
      const double a = r->rows[i * nB + k].point.K_cr, b = bf.KCritical(r->b_grid[k]);
      if (b > 0 && std::isfinite(b)) err = std::max(err, std::abs(a / b - 1));
      else if (a != b) err = std::max(err, 1.0);
    }
  }
  state.counters["max_rel_err_K_cr_vs_brute_force"] = err;
  state.counters["rows"] = static_cast<double>(r->rows.size());
  state.counters["params"] = n;
}
BENCHMARK(BM_RunBoundary)->DenseRange(0, 4)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// Delta-method std at d = 2 on Table I with a seeded covariance (1% relative
// std): K_CR(B) on a 1000-point grid plus the four summary quantities (both
// by implicit differentiation, SummaryStdDelta). Error: largest relative
// change of the summary std when the difference step of W_x is halved.
void BM_DeltaMethodStd(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  const int n = stability::NumLogParameters(p);
  std::vector<double> cov(n * n, 0.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int i = 0; i < n; ++i) cov[i * n + i] = 1e-4 * (1.0 + 0.5 * std::abs(g(rng)));
  const stability::ZWidth z(p, 1e-3, 2);
  const stability::DelaySummary s = z.Summarize();
  std::vector<stability::CriticalPoint> pts;
  for (int i = 0; i < 1000; ++i) pts.push_back(z.At(1.05 * s.B_max * i / 999.0));
  stability::SummaryStd sd;
  for (auto _ : state) {
    benchmark::DoNotOptimize(stability::KcrStd(p, cov, 1e-3, 2, pts).data());
    sd = stability::SummaryStdDelta(p, cov, 1e-3, 2, s);
  }
  stability::UncertaintyOptions half;
  half.log_step = 5e-5;
  const stability::SummaryStd h = stability::SummaryStdDelta(p, cov, 1e-3, 2, s, half);
  double err = 0;
  for (auto [a, b] : {std::pair{sd.K_cr_at_zero_B, h.K_cr_at_zero_B}, {sd.B_t, h.B_t}, {sd.K_cr_max, h.K_cr_max},
                      {sd.B_max, h.B_max}}) {
    err = std::max(err, std::abs(a / b - 1));
  }
  state.counters["max_rel_change_half_step"] = err;
}
BENCHMARK(BM_DeltaMethodStd)->Unit(benchmark::kMillisecond);

// The summary std (K_CR(0), B_t, K_CR^max, B_max) of one delay against the
// number of sections, 0-4 (2-18 log parameters): Table I's rigid body, its
// two sections, and sections added at 45 and 70 Hz (pole 8 % above its zero,
// zeta 0.1), d = 2, a seeded diagonal covariance (1 % relative std); the
// nominal Z-width and the perturbed plants are built once, outside the loop
// (run shares them; PlantWithSections above BM_RunBoundary). Arg 1: 0 = SummaryStdDelta (implicit differentiation on
// the nominal crossings, finite differences only where they do not apply),
// 1 = SummaryStdFiniteDifference (2 p perturbed Z-widths). Error: the largest
// relative difference between the two (the differences' truncation error).
void BM_SummaryStd(benchmark::State& state) {
  const model::Plant p = PlantWithSections(static_cast<int>(state.range(0)));
  const int n = stability::NumLogParameters(p);
  std::vector<double> cov(n * n, 0.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int i = 0; i < n; ++i) cov[i * n + i] = 1e-4 * (1.0 + 0.5 * std::abs(g(rng)));
  const stability::PerturbedPlants pl = stability::SamplePerturbedPlants(p, 1e-3);
  const stability::ZWidth z(pl.nominal, 2);
  const stability::DelaySummary s = z.Summarize();
  stability::SummaryStd sd;
  for (auto _ : state) {
    sd = state.range(1) == 0 ? stability::SummaryStdDelta(z, pl, cov, 2, s)
                             : stability::SummaryStdFiniteDifference(pl, cov, 2, s);
    benchmark::DoNotOptimize(sd);
  }
  const stability::SummaryStd im = stability::SummaryStdDelta(z, pl, cov, 2, s);
  const stability::SummaryStd fd = stability::SummaryStdFiniteDifference(pl, cov, 2, s);
  double err = 0;
  for (auto [a, b] : {std::pair{im.K_cr_at_zero_B, fd.K_cr_at_zero_B}, {im.B_t, fd.B_t}, {im.K_cr_max, fd.K_cr_max},
                      {im.B_max, fd.B_max}}) {
    if (std::isfinite(b) && b > 0) err = std::max(err, std::abs(a / b - 1));
  }
  state.counters["params"] = n;
  state.counters["max_rel_diff_implicit_vs_fd"] = err;
}
BENCHMARK(BM_SummaryStd)->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1}})->Unit(benchmark::kMillisecond);

// The relay experiment at d = 2: record length (s) against the error of the
// estimate and of the paper's reading, at B = 0 and 0.9 B_t (where the plain
// relay locks onto a cycle 40 samples long).
void BM_Relay(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  const stability::ZWidth z(p, 1e-3, 2);
  stability::RelayOptions o;
  o.delay_samples = 2;
  o.seconds = static_cast<double>(state.range(0));
  o.damping = 0.01 * static_cast<double>(state.range(1)) * z.Summarize().B_t;
  stability::RelayResult r;
  for (auto _ : state) {
    r = stability::SimulateRelay(p, o);
    benchmark::DoNotOptimize(r.K_cr);
  }
  const stability::CriticalPoint c = z.At(o.damping);
  state.counters["rel_err_K_cr"] = std::abs(r.K_cr / c.K_cr - 1);
  state.counters["rel_err_f_cr"] = std::abs(r.f_cr_hz / c.f_cr_hz - 1);
  state.counters["paper_rel_err_K"] = std::abs(r.K_cr_peak / c.K_cr - 1);
  state.counters["paper_rel_err_f"] = std::abs(r.f_cr_peak_hz / c.f_cr_hz - 1);
  state.counters["uncertainty"] = r.uncertainty;
  state.counters["runs"] = r.relay_runs;
}
BENCHMARK(BM_Relay)->ArgsProduct({{10, 30, 120}, {0, 90}})->Unit(benchmark::kMillisecond);

// The relay on the haptic loop (issue 16): Table I at d = 4 with a 50 Hz
// velocity low-pass and a hand (M = 0.3 m, B = b, K giving 2 Hz), record
// length (s) against the error of the estimate from the exact Z-width of the
// same loop, at B = 0.5 B_t of that loop (of B_max_from_zero: it has no B_t).
void BM_RelayLoop(benchmark::State& state) {
  const model::Plant p = model::PhantomTable1();
  stability::RelayOptions o;
  o.delay_samples = 4;
  o.seconds = static_cast<double>(state.range(0));
  stability::SetLowPassFilter(50.0, 1e-3, &o.loop);
  const double w = 2 * std::numbers::pi * 2.0;
  o.loop.hand = {0.3 * p.m, p.b, w * w * 1.3 * p.m};
  const stability::ZWidth z(p, 1e-3, 4, o.loop);
  const stability::DelaySummary s = z.Summarize();
  o.damping = 0.5 * (std::isfinite(s.B_t) ? s.B_t : s.B_max_from_zero);
  stability::RelayResult r;
  for (auto _ : state) {
    r = stability::SimulateRelay(p, o);
    benchmark::DoNotOptimize(r.K_cr);
  }
  const stability::CriticalPoint c = z.At(o.damping);
  state.counters["rel_err_K_cr"] = std::abs(r.K_cr / c.K_cr - 1);
  state.counters["rel_err_f_cr"] = std::abs(r.f_cr_hz / c.f_cr_hz - 1);
  state.counters["paper_rel_err_K"] = std::abs(r.K_cr_peak / c.K_cr - 1);
  state.counters["refined"] = r.refined();
  state.counters["runs"] = r.relay_runs;
}
BENCHMARK(BM_RelayLoop)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace zwidth

BENCHMARK_MAIN();
