#include "analysis/run.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

#include "analysis/laps.h"
#include "io/reference_models.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "model/parallel.h"
#include "stability/uncertainty.h"
#include "stability/velocity_filter.h"

namespace zwidth::analysis {
namespace {

// The model's sampled response g at every bin, phases unwrapped along
// frequency (the model's continuously; the measured one kept within half a
// turn of the model's).
BodeData MakeBode(const ident::FrequencyResponse& frf, const stability::SampledPlant& g, double T) {
  BodeData b;
  double pm_prev = 0.0;
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    const double th = 2 * std::numbers::pi * frf.f_hz[k] * T;
    const auto gm = g.AtTheta(th);
    double pm = std::arg(gm) * 180 / std::numbers::pi;
    if (k > 0) pm += 360.0 * std::round((pm_prev - pm) / 360.0);
    pm_prev = pm;
    double ph = std::arg(frf.H[k]) * 180 / std::numbers::pi;
    ph += 360.0 * std::round((pm - ph) / 360.0);
    b.H_abs.push_back(std::abs(frf.H[k]));
    b.H_phase_deg.push_back(ph);
    b.G_abs.push_back(std::abs(gm));
    b.G_phase_deg.push_back(pm);
  }
  return b;
}

// The std of ln G per bin (real part: ln|G|, imaginary: phase in rad) by the
// delta method: g_i = d ln G / d x_i by central differences in the log
// parameters x (step h, as stability/uncertainty.h uses), var = g^T C g for
// the real and the imaginary parts apart. The model is sampled (ZOH) as the fit
// and the figure use it.
void AddModelBand(const io::ModelFile& model, const ident::FrequencyResponse& frf, double T, BodeData* b) {
  const size_t p = static_cast<size_t>(stability::NumLogParameters(model.plant));
  if (model.log_covariance.size() != p * p) return;
  constexpr double h = 1e-5;
  const size_t n = frf.f_hz.size();
  std::vector<std::vector<std::complex<double>>> g(p, std::vector<std::complex<double>>(n));
  ParallelFor(p, [&](size_t i) {
    std::vector<double> dx(p, 0.0);
    dx[i] = h;
    const stability::SampledPlant plus(stability::PerturbLog(model.plant, dx), T);
    dx[i] = -h;
    const stability::SampledPlant minus(stability::PerturbLog(model.plant, dx), T);
    for (size_t k = 0; k < n; ++k) {
      const double th = 2 * std::numbers::pi * frf.f_hz[k] * T;
      g[i][k] = std::log(plus.AtTheta(th) / minus.AtTheta(th)) / (2 * h);
    }
  });
  b->G_log_abs_std.assign(n, 0.0);
  b->G_phase_std_deg.assign(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    double vr = 0.0, vi = 0.0;
    for (size_t r = 0; r < p; ++r) {
      for (size_t c = 0; c < p; ++c) {
        const double cv = model.log_covariance[r * p + c];
        vr += g[r][k].real() * cv * g[c][k].real();
        vi += g[r][k].imag() * cv * g[c][k].imag();
      }
    }
    b->G_log_abs_std[k] = std::sqrt(std::max(vr, 0.0));
    b->G_phase_std_deg[k] = std::sqrt(std::max(vi, 0.0)) * 180 / std::numbers::pi;
  }
}

// The loop figure's two loops of one delay: the raw backward difference (the
// run's own ZWidth when the run has no filter) and the report's low-pass, with
// their passivity bounds, and the figure's upper B.
struct LoopWork {
  std::optional<stability::ZWidth> raw_own, filtered;
  const stability::ZWidth* raw = nullptr;
  std::optional<stability::Passivity> passive_raw, passive_filtered;
  double top = 0.0;  // the last of the 300 B values [N m s/rad]
};

constexpr int kLoopFigureB = 300;  // B values of the loop figure, 0 to top
constexpr size_t kChunks = 4;      // parts of a curve or a loop quantity, as separate tasks

// [first, last) of part c of n items in kChunks parts.
std::pair<size_t, size_t> Chunk(size_t n, size_t c) { return {n * c / kChunks, n * (c + 1) / kChunks}; }

// The figure data other than the Bode plot: the K_CR curves of the reference
// (`reference`, its ZWidth per delay; none without) and of the rigid body on
// the run's B grid, and the loop figure (without and with the report's
// velocity filter, the run's hand in both, on 300 B values to 1.05 x the
// larger B_max). Work goes out as small independent tasks in two rounds (the
// loop figure's B values need its loops' B_max first), so that the threads
// stay busy; every value is computed as a plain loop would and written to its
// own slot.
void CurvesAndLoops(const RunAnalysis& a, const std::vector<stability::ZWidth>& reference,
                    const std::vector<stability::ZWidth>& rigid, FigureData* f) {
  const double T = a.period_s;
  const stability::LoopOptions& loop = a.options.loop;
  const PlantStability& st = a.stability;
  const size_t nd = st.delays.size(), nB = st.b_grid.size();
  stability::LoopOptions lf, lr;
  lf.hand = lr.hand = loop.hand;
  stability::SetLowPassFilter(a.options.report_filter_hz, T, &lf);
  std::vector<LoopWork> work(nd);
  if (!reference.empty()) f->kcr_reference.assign(nd, std::vector<stability::CriticalPoint>(nB));
  f->kcr_rigid.assign(nd, std::vector<stability::CriticalPoint>(nB));
  const size_t curve_sets = reference.empty() ? 1 : 2;
  // Round 1: the loops, their B_max and passivity (one task per delay, the
  // longest delays first), then the K_CR curves in chunks.
  ParallelFor(nd + curve_sets * nd * kChunks, [&](size_t t) {
    if (t < nd) {
      const size_t i = nd - 1 - t;
      LoopWork& w = work[i];
      if (loop.HasFilter()) w.raw_own.emplace(st.sampled, st.delays[i], lr);
      w.raw = w.raw_own ? &*w.raw_own : &st.zwidths[i];
      w.filtered.emplace(st.sampled, st.delays[i], lf);
      w.passive_filtered.emplace(a.input.model.plant.b, T, w.filtered->total_delay(), lf);
      w.passive_raw.emplace(a.input.model.plant.b, T, w.raw->total_delay(), lr);
      // Without a filter the run's summary is the raw loop's.
      const double bm = std::max(loop.HasFilter() ? w.raw->Summarize().B_max : st.summaries[i].B_max,
                                 w.filtered->Summarize().B_max);
      w.top = std::isfinite(bm) && bm > 0 ? 1.05 * bm : st.b_grid.back();
      return;
    }
    t -= nd;
    const bool rigid_set = t / (nd * kChunks) == curve_sets - 1;
    const size_t i = t % (nd * kChunks) / kChunks;
    const auto [k0, k1] = Chunk(nB, t % kChunks);
    const stability::ZWidth& z = rigid_set ? rigid[i] : reference[i];
    std::vector<stability::CriticalPoint>& out = rigid_set ? f->kcr_rigid[i] : f->kcr_reference[i];
    for (size_t k = k0; k < k1; ++k) out[k] = z.At(st.b_grid[k]);
  });
  // Round 2: per delay the B values, then each of the four quantities in chunks.
  f->loop.assign(nd, {});
  for (size_t i = 0; i < nd; ++i) {
    LoopFigureDelay& d = f->loop[i];
    for (int k = 0; k < kLoopFigureB; ++k) d.B.push_back(work[i].top * k / (kLoopFigureB - 1.0));
    d.raw.resize(kLoopFigureB);
    d.filtered.resize(kLoopFigureB);
    d.K_passive_raw.resize(kLoopFigureB);
    d.K_passive_filtered.resize(kLoopFigureB);
  }
  ParallelFor(nd * 4 * kChunks, [&](size_t t) {
    const size_t i = t / (4 * kChunks), what = t / kChunks % 4;
    const auto [k0, k1] = Chunk(kLoopFigureB, t % kChunks);
    const LoopWork& w = work[i];
    LoopFigureDelay& d = f->loop[i];
    for (size_t k = k0; k < k1; ++k) {
      const double B = d.B[k];
      switch (what) {
        case 0: d.raw[k] = w.raw->StableIntervals(B); break;
        case 1: d.filtered[k] = w.filtered->StableIntervals(B); break;
        case 2: d.K_passive_raw[k] = w.passive_raw->KHi(B); break;
        default: d.K_passive_filtered[k] = w.passive_filtered->KHi(B); break;
      }
    }
  });
}

// reference: the reference's Z-width per delay (none without a reference).
FigureData MakeFigures(const RunAnalysis& a, const std::vector<stability::ZWidth>& reference) {
  FigureData f;
  const double T = a.period_s;
  // The model's own sampled response (the loop's hand is not part of it).
  const bool plain_hand = a.options.loop.hand.IsNone();
  f.bode = plain_hand ? MakeBode(a.input.response.frf, a.stability.sampled, T)
                      : MakeBode(a.input.response.frf, stability::SampledPlant(a.input.model.plant, T), T);
  AddModelBand(a.input.model, a.input.response.frf, T, &f.bode);
  model::Plant rigid = a.input.model.plant;
  rigid.modes.clear();
  const stability::SampledPlant rigid_sampled(rigid, T);
  std::vector<stability::ZWidth> rigid_zs;
  for (int d : a.options.delays) rigid_zs.emplace_back(rigid_sampled, d);
  CurvesAndLoops(a, reference, rigid_zs, &f);
  return f;
}

}  // namespace

ReferenceStability ReferenceStabilityOf(const io::ModelFile& reference, double T, const std::vector<int>& delays) {
  ReferenceStability r;
  r.period_s = T;
  r.delays = delays;
  const stability::SampledPlant sampled(reference.plant, T);
  for (int d : delays) r.zwidths.emplace_back(sampled, d);
  r.summaries.resize(delays.size());
  ParallelFor(delays.size(), [&](size_t i) { r.summaries[i] = r.zwidths[i].Summarize(); });
  return r;
}

bool RunOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (const std::string problem = io::LoopDelaysProblem(delays, "RunOptions::delays"); !problem.empty()) {
    return fail(problem);
  }
  if (figures && !(std::isfinite(report_filter_hz) && report_filter_hz > 0))
    return fail("RunOptions::report_filter_hz must be > 0 and finite");
  if (table2 && !table2->IsValid(why)) return false;
  return grid.IsValid(why);
}

RunAnalysis Analyse(RunInput input, const RunOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  if (input.fit.status != fit::FitStatus::kConverged) throw ComputationError(input.fit.message);
  Laps laps;
  input.model.linear = o.linear;  // the model file keeps the run's units
  if (input.reference) {  // before the Z-width: a reference of the other kind is refused
    CheckSameUnits(o.linear, *input.reference, "the fitted model",
                   "the reference " + (input.reference_name.empty() ? std::string("model") : input.reference_name));
  }
  input.response.frf.used_by_fit = input.fit.band.used;
  const double T = input.response.frf.period_s();
  if (o.figures && !(o.report_filter_hz < 0.5 / T)) {  // before the Z-width, not at the figures
    std::ostringstream msg;
    msg << "RunOptions::report_filter_hz " << o.report_filter_hz << " Hz must be below the log's Nyquist frequency "
        << 0.5 / T << " Hz";
    throw InputError(msg.str());
  }
  // The model's Z-width per delay, computed once for the summary, the
  // comparison, the boundary rows and the figures.
  // With Coulomb friction in the model, A* along the boundary (default
  // options on the run's loop, with the encoder step read from the log).
  PlantStabilityOptions po;
  po.delays = o.delays;
  po.loops = {o.loop};
  po.grid = o.grid;
  po.friction = input.model.friction;
  po.amplitude.encoder_step = EncoderStepOf(input.model, std::nullopt);
  RunAnalysis a(AnalysePlantStability(input.model, T, po));
  a.input = std::move(input);
  a.options = o;
  a.period_s = T;
  const double ms = laps.Lap(), friction_ms = a.stability.friction_amplitude_ms;
  a.stages.push_back({"boundary", ms - friction_ms});
  if (!a.stability.friction_amplitudes.empty()) a.stages.push_back({"friction amplitude", friction_ms});
  std::vector<stability::ZWidth> ref_zs;  // the reference on the paper's loop, per delay
  if (a.input.reference) {
    const io::ModelFile& ref = *a.input.reference;
    std::optional<ReferenceStability>& given = a.input.reference_stability;
    const bool computed_here = !given || given->period_s != T || given->delays != o.delays;
    if (computed_here) given = ReferenceStabilityOf(ref, T, o.delays);
    ref_zs = std::move(given->zwidths);
    const std::vector<stability::DelaySummary> ref_sums = std::move(given->summaries);
    given.reset();
    const PlantStability& st = a.stability;
    const bool plain = !o.loop.HasFilter() && o.loop.hand.IsNone();
    const DelayStability model_st =
        plain ? DelayStability{st.summaries, st.stds, st.has_std} : SummarizeDelays(a.input.model, T, o.delays);
    a.comparison = CompareModels(a.input.model, ref, o.delays, model_st, ref_sums, o.linear);
    a.stages.push_back({computed_here ? "compare (reference Z-width)" : "compare", laps.Lap()});
  }
  if (o.table2) {
    a.table2 = CompareTable2(a.stability.sampled.plant(), T, io::Table2Points(), *o.table2);
    a.stages.push_back({"Table II (relay runs)", laps.Lap()});
  }
  if (o.figures) {
    a.figures = MakeFigures(a, ref_zs);
    a.stages.push_back({"figure data (reference, rigid)", laps.Lap()});
  }
  return a;
}

std::string FitReport(const fit::FitResult& r) {
  std::ostringstream os;
  os << "band: " << r.band.Describe() << "\n";
  if (!r.delay_choice.empty()) os << r.delay_choice << "\n";
  if (!r.order_table.empty()) {
    char line[400];
    os << "order search (stabilisation table; * = pole within 2% of one at the order below):\n";
    std::snprintf(line, sizeof line, "  %5s %10s %12s  %s\n", "modes", "chi2/dof", "BIC", "poles [Hz]; rejected because");
    os << line;
    for (const fit::OrderTrial& t : r.order_table) {
      std::string poles;
      for (size_t i = 0; i < t.pole_hz.size(); ++i) {
        char p[40];
        std::snprintf(p, sizeof p, "%s%.4g%s", i ? " " : "", t.pole_hz[i], t.persists[i] ? "*" : "");
        poles += p;
      }
      if (!t.spurious.empty()) poles += (poles.empty() ? "" : "; ") + t.spurious.front();
      if (t.spurious.size() > 1) poles += " (+" + std::to_string(t.spurious.size() - 1) + " more)";
      std::snprintf(line, sizeof line, "  %5d %10.4g %12.6g  %s\n", t.num_modes, t.chi2_per_dof, t.bic, poles.c_str());
      os << line;
    }
    os << "chosen: " << r.order_choice << "\n";
  }
  os << "quality: " << fit::ToString(r.quality) << "\n";
  for (const fit::QualityReason& q : r.reasons) os << "  - " << q.message << "\n    advice: " << q.advice << "\n";
  return os.str();
}

}  // namespace zwidth::analysis
