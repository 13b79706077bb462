// Starting points of the fit: the rigid body from the low band, sections at
// the prominent peaks and notches of |H / G_rigid|, the linear rational start,
// and, from a fit of one section fewer, sections grown where its misfit peaks.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "fit/fit_internal.h"
#include "model/zoh_modal.h"

namespace zwidth::fit::internal {

// Rigid body from the lowest 5% of the band: 1/G(jw) = -m w^2 + j b w, after
// undoing the ZOH's half-sample and the input delay's phase.
model::Plant EstimateRigid(const ident::FrequencyResponse& frf, int delay) {
  const double T = frf.period_s();
  const double f_lo = frf.f_hz.front(), f_hi = frf.f_hz.back();
  const double limit = f_lo + 0.05 * (f_hi - f_lo);
  double sm_num = 0, sm_den = 0, sb_num = 0, sb_den = 0;
  for (size_t k = 0; k < frf.f_hz.size() && (frf.f_hz[k] <= limit || k < 4); ++k) {
    const double w = 2.0 * std::numbers::pi * frf.f_hz[k];
    const cd Y = std::polar(1.0, -w * T * (delay + 0.5)) / frf.H[k];
    const double wt = std::max(frf.coherence[k], 1e-3);
    sm_num += wt * (-Y.real()) * w * w;
    sm_den += wt * w * w * w * w;
    sb_num += wt * Y.imag() * w;
    sb_den += wt * w * w;
  }
  model::Plant p;
  p.m = sm_num / sm_den;
  if (!(p.m > 0.0) || !std::isfinite(p.m)) {
    // Fall back on the magnitude alone.
    const double w = 2.0 * std::numbers::pi * frf.f_hz.front();
    p.m = 1.0 / (std::abs(frf.H.front()) * w * w);
  }
  p.b = sb_num / sb_den;
  const double b_min = p.m * 2.0 * std::numbers::pi * 0.01 * std::max(f_lo, 1e-3);
  if (!(p.b > b_min) || !std::isfinite(p.b)) p.b = p.m * 2.0 * std::numbers::pi * 0.5 * f_lo;
  return p;
}

// Topographic prominence of the local maxima of v.
std::vector<Extremum> Peaks(const std::vector<double>& v) {
  std::vector<Extremum> out;
  const size_t n = v.size();
  for (size_t i = 1; i + 1 < n; ++i) {
    if (!(v[i] > v[i - 1] && v[i] >= v[i + 1])) continue;
    double left_min = v[i], right_min = v[i];
    for (size_t j = i; j-- > 0;) { if (v[j] > v[i]) break; left_min = std::min(left_min, v[j]); }
    for (size_t j = i + 1; j < n; ++j) { if (v[j] > v[i]) break; right_min = std::min(right_min, v[j]); }
    out.push_back({i, v[i] - std::max(left_min, right_min)});
  }
  std::sort(out.begin(), out.end(), [](const Extremum& a, const Extremum& b) { return a.prominence > b.prominence; });
  return out;
}

std::vector<model::Plant> AutomaticStarts(const ident::FrequencyResponse& frf, int n, int delay, int max_starts) {
  const model::Plant rigid = EstimateRigid(frf, delay);
  std::vector<model::Plant> starts;
  if (n == 0) { starts.push_back(rigid); return starts; }
  const double T = frf.period_s();
  const double nyq_w = std::numbers::pi / T;
  // R = H / G_rigid,d: the sections' product, with unit gain at low frequency.
  model::ZohModalForm<double> rf;
  rf.Build(rigid.m, rigid.b, nullptr, 0, T);
  const size_t nb = frf.f_hz.size();
  std::vector<double> logr(nb), wgt(nb);
  for (size_t k = 0; k < nb; ++k) {
    const double theta = 2.0 * std::numbers::pi * frf.f_hz[k] * T;
    const model::Cx<double> g = rf.At(std::cos(theta), std::sin(theta));
    const cd gr = cd(g.re, g.im) * std::polar(1.0, -theta * delay);
    logr[k] = std::log(std::abs(frf.H[k] / gr));
    wgt[k] = std::max(frf.coherence[k], 1e-6);
  }
  // Coherence-weighted smoothing over about 1% of the band.
  const int h = std::max<int>(1, static_cast<int>(nb / 200));
  std::vector<double> sm(nb);
  for (size_t k = 0; k < nb; ++k) {
    double a = 0, w = 0;
    for (int j = -h; j <= h; ++j) {
      const long i = static_cast<long>(k) + j;
      if (i < 0 || i >= static_cast<long>(nb)) continue;
      a += wgt[i] * logr[i];
      w += wgt[i];
    }
    sm[k] = a / w;
  }
  std::vector<double> neg(nb);
  for (size_t k = 0; k < nb; ++k) neg[k] = -sm[k];
  const std::vector<Extremum> peaks = Peaks(sm), notches = Peaks(neg);
  auto omega_of = [&](size_t k) { return std::min(2.0 * std::numbers::pi * frf.f_hz[k], 0.9 * nyq_w); };
  // Candidate sets: the n most prominent, then with the next candidates swapped in.
  auto pick = [&](const std::vector<Extremum>& ex, int skip) {
    std::vector<double> w;
    for (size_t i = 0; i < ex.size() && static_cast<int>(w.size()) < n; ++i) {
      if (skip >= 0 && static_cast<int>(i) == skip && ex.size() > static_cast<size_t>(n)) continue;
      w.push_back(omega_of(ex[i].index));
    }
    // Too few extrema: spread the rest over the upper band.
    const double f_top = 2.0 * std::numbers::pi * frf.f_hz.back();
    for (int i = static_cast<int>(w.size()); i < n; ++i) w.push_back(f_top * (0.5 + 0.4 * i / std::max(1, n)));
    std::sort(w.begin(), w.end());
    return w;
  };
  auto make = [&](const std::vector<double>& wp, const std::vector<double>& wz, double zeta) {
    model::Plant p = rigid;
    for (int i = 0; i < n; ++i) p.modes.push_back({wp[i], 2.0 * zeta * wp[i], wz[i], 2.0 * zeta * wz[i]});
    return p;
  };
  const std::vector<double> wp = pick(peaks, -1), wz = pick(notches, -1);
  starts.push_back(make(wp, wz, 0.1));
  // Second: the linear rational (Sanathanan-Koerner) fit converted to eq. (1),
  // which does not depend on spotting peaks that closely spaced or interlaced
  // modes hide. It takes the place of the last peak-swap start.
  if (max_starts > 1) {
    if (std::optional<model::Plant> sk = LinearRationalStart(frf, n, delay)) starts.push_back(*sk);
  }
  for (double zeta : {0.03, 0.3}) starts.push_back(make(wp, wz, zeta));
  for (int s = n - 1; s >= 0 && static_cast<int>(starts.size()) < max_starts + 2; --s) {
    starts.push_back(make(pick(peaks, s), wz, 0.1));
    starts.push_back(make(wp, pick(notches, s), 0.1));
  }
  // A generic start: antiresonance just below each resonance, spread in log f.
  {
    std::vector<double> gp(n), gz(n);
    const double lo = std::log(2.0 * std::numbers::pi * std::max(frf.f_hz.front(), frf.f_hz.back() / 50));
    const double hi = std::log(2.0 * std::numbers::pi * frf.f_hz.back());
    for (int i = 0; i < n; ++i) {
      gp[i] = std::exp(lo + (hi - lo) * (i + 0.6) / n);
      gz[i] = 0.85 * gp[i];
    }
    starts.push_back(make(gp, gz, 0.1));
  }
  if (static_cast<int>(starts.size()) > max_starts) starts.resize(max_starts);
  return starts;
}

// Starts for n + 1 sections from an n-section fit: its sections kept, a new
// one placed where the weighted misfit peaks (the unmodelled mode's
// resonance/antiresonance pair sits there), as a pole above a zero and as a
// zero above a pole, at the three largest misfit peaks; and each section
// split in two.
std::vector<model::Plant> GrowStarts(const Fixed& prev) {
  std::vector<model::Plant> out;
  const size_t nb = prev.r.size();
  if (nb < 8) return out;
  const int h = std::max<int>(2, static_cast<int>(nb / 100));
  std::vector<double> sm(nb);
  for (size_t k = 0; k < nb; ++k) {
    double a = 0; int c = 0;
    for (long j = static_cast<long>(k) - h; j <= static_cast<long>(k) + h; ++j) {
      if (j < 0 || j >= static_cast<long>(nb)) continue;
      a += std::norm(prev.r[j]); ++c;
    }
    sm[k] = a / c;
  }
  const std::vector<Extremum> peaks = Peaks(sm);
  for (size_t i = 0; i < peaks.size() && i < 3; ++i) {
    const double w = kHz * prev.f_hz[peaks[i].index];
    for (const auto& [fp, fz] : {std::pair{1.08, 0.92}, std::pair{1.0, 0.8}, std::pair{1.25, 1.0}}) {
      model::Plant p = prev.res.plant;
      p.modes.push_back({w * fp, 2 * 0.05 * w * fp, w * fz, 2 * 0.05 * w * fz});
      CanonicalOrder(&p, nullptr);
      out.push_back(p);
    }
  }
  // Each section split in two, 8 % apart (two close modes that the smaller
  // fit merged into one).
  for (size_t i = 0; i < prev.res.plant.modes.size(); ++i) {
    model::Plant p = prev.res.plant;
    const model::Mode m = p.modes[i];
    p.modes[i] = {m.omega * 0.92, m.c * 0.5, m.v * 0.92, m.d * 0.5};
    p.modes.push_back({m.omega * 1.08, m.c * 0.5, m.v * 1.08, m.d * 0.5});
    CanonicalOrder(&p, nullptr);
    out.push_back(p);
  }
  return out;
}

}  // namespace zwidth::fit::internal
