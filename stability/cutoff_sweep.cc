#include "stability/cutoff_sweep.h"

#include <algorithm>
#include <cmath>

#include "model/error.h"
#include "stability/velocity_filter.h"

namespace zwidth::stability {

std::string ToString(SweepMeasure m) { return m == SweepMeasure::kKcrMax ? "kcr-max" : "area"; }

SweepMeasure SweepMeasureFromString(const std::string& s) {
  if (s == "kcr-max") return SweepMeasure::kKcrMax;
  if (s == "area") return SweepMeasure::kArea;
  throw InputError("measure '" + s + "': expected kcr-max or area");
}

bool CutoffSweepOptions::IsValid(double T, std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (cutoffs_hz.empty()) return bad("cutoffs_hz is empty");
  for (double f : cutoffs_hz) {
    if (!(f > 0.0 && f < 0.5 / T)) return bad("cutoffs_hz: each cut-off must be in (0, Nyquist)");
  }
  if (measure == SweepMeasure::kArea && !(area_B_max > 0.0 && std::isfinite(area_B_max))) {
    return bad("area_B_max must be finite and > 0 for the area measure");
  }
  if (area_B_max > kMaxLoopValue) {  // a hand's and a wall's B bound: 1e300 was swept
    return bad("CutoffSweepOptions::area_B_max must be at most 1e12 (N m s/rad), the bound of a loop's B");
  }
  if (!(area_K_clip > 0.0)) return bad("area_K_clip must be > 0");
  if (area_B_points < 2) return bad("area_B_points must be >= 2");
  return true;
}

double StableArea(const ZWidth& z, double B_max, double K_clip, int points) {
  double area = 0.0, prev = 0.0;
  for (int i = 0; i < points; ++i) {
    const double B = B_max * i / (points - 1);
    double len = 0.0;
    for (const KInterval& iv : z.StableIntervals(B)) len += std::min(iv.K_hi, K_clip) - std::min(iv.K_lo, K_clip);
    if (i > 0) area += 0.5 * (len + prev) * (B_max / (points - 1));
    prev = len;
  }
  return area;
}

CutoffSweepResult SweepCutoff(const model::Plant& plant, double T, int delay, const LoopOptions& loop,
                              const CutoffSweepOptions& o) {
  std::string why;
  if (!o.IsValid(T, &why)) throw InputError("cut-off sweep: " + why);
  CutoffSweepResult r;
  for (double f : o.cutoffs_hz) {
    LoopOptions l = loop;
    SetLowPassFilter(f, T, &l);
    const ZWidth z(plant, T, delay, l);
    r.cutoffs_hz.push_back(f);
    if (o.measure == SweepMeasure::kKcrMax) {
      r.summaries.push_back(z.Summarize());
      r.measure.push_back(r.summaries.back().K_cr_max);
    } else {
      r.summaries.push_back(DelaySummary{});
      r.measure.push_back(StableArea(z, o.area_B_max, o.area_K_clip, o.area_B_points));
    }
    const double m = r.measure.back();
    if (std::isfinite(m) && (r.best < 0 || m > r.measure[r.best])) r.best = static_cast<int>(r.measure.size()) - 1;
  }
  r.best_at_edge = r.best == 0 || (r.best >= 0 && r.best + 1 == static_cast<int>(r.measure.size()));
  LoopOptions raw = loop;
  raw.filter_b.clear();
  raw.filter_a.clear();
  const ZWidth z0(plant, T, delay, raw);
  r.unfiltered = o.measure == SweepMeasure::kKcrMax ? z0.Summarize().K_cr_max
                                                    : StableArea(z0, o.area_B_max, o.area_K_clip, o.area_B_points);
  return r;
}

}  // namespace zwidth::stability
