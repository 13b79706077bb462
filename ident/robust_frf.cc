#include "ident/robust_frf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "model/error.h"

namespace zwidth::ident {

using cd = std::complex<double>;

namespace {

// The DFT of x[offset .. offset + n) at bins 0..n/2 (direct: a period is short
// and the lines few, and this keeps the file free of FFTW plans).
std::vector<cd> PeriodDft(const std::vector<double>& x, size_t offset, int n, const std::vector<int>& bins) {
  std::vector<cd> out(bins.size());
  for (size_t b = 0; b < bins.size(); ++b) {
    const double w = -2.0 * std::numbers::pi * bins[b] / n;
    cd s = 0.0;
    for (int t = 0; t < n; ++t) s += x[offset + t] * std::polar(1.0, w * t);
    out[b] = s;
  }
  return out;
}

}  // namespace

RobustEstimate EstimateRobust(const std::vector<LocalRecord>& runs, double fs, int N) {
  if (runs.empty()) throw InputError("the robust method needs at least one realisation");
  if (!(fs > 0.0) || !std::isfinite(fs)) throw InputError("sample rate must be finite and > 0");
  if (N < 4) throw InputError("period_samples = " + std::to_string(N) + ": must be >= 4");
  size_t n = runs[0].u.size();
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].u.size() != runs[i].y.size()) {
      throw InputError("realisation " + std::to_string(i + 1) + ": the input and output have different lengths");
    }
    n = std::min(n, runs[i].u.size());
  }
  const int P = static_cast<int>(n / static_cast<size_t>(N)), M = static_cast<int>(runs.size());
  if (P < 2) {
    throw InputError("the records hold " + std::to_string(P) + " whole period(s) of " + std::to_string(N) +
                     " samples: the robust method needs at least 2 (record more periods)");
  }
  // Excited lines: the input's power over all periods and realisations.
  std::vector<int> all;
  for (int k = 1; k <= (N - 1) / 2; ++k) all.push_back(k);
  std::vector<double> power(all.size(), 0.0);
  for (const LocalRecord& r : runs) {
    for (int p = 0; p < P; ++p) {
      const std::vector<cd> U = PeriodDft(r.u, static_cast<size_t>(p) * N, N, all);
      for (size_t b = 0; b < all.size(); ++b) power[b] += std::norm(U[b]);
    }
  }
  const double top = *std::max_element(power.begin(), power.end());
  std::vector<int> lines;
  for (size_t b = 0; b < all.size(); ++b) {
    if (top > 0.0 && power[b] >= 1e-6 * top) lines.push_back(all[b]);
  }
  if (lines.empty()) throw InputError("no excited line: the input is zero over the periods");
  const size_t L = lines.size();
  std::vector<double> suu(L, 0.0), syy(L, 0.0);
  std::vector<cd> suy(L, 0.0);
  const double psd = 2.0 / (fs * N * static_cast<double>(M));  // one-sided, averaged over the realisations
  std::vector<std::vector<cd>> G(M, std::vector<cd>(L));
  std::vector<std::vector<double>> var_n(M, std::vector<double>(L));
  for (int m = 0; m < M; ++m) {
    std::vector<std::vector<cd>> U(P), Y(P);
    for (int p = 0; p < P; ++p) {
      U[p] = PeriodDft(runs[m].u, static_cast<size_t>(p) * N, N, lines);
      Y[p] = PeriodDft(runs[m].y, static_cast<size_t>(p) * N, N, lines);
    }
    for (size_t l = 0; l < L; ++l) {
      cd um = 0.0, ym = 0.0;
      for (int p = 0; p < P; ++p) {
        um += U[p][l];
        ym += Y[p][l];
      }
      um /= P;
      ym /= P;
      suu[l] += psd * std::norm(um);
      syy[l] += psd * std::norm(ym);
      suy[l] += psd * std::conj(um) * ym;
      double vu = 0.0, vy = 0.0;
      cd cyu = 0.0;
      for (int p = 0; p < P; ++p) {
        const cd du = U[p][l] - um, dy = Y[p][l] - ym;
        vu += std::norm(du);
        vy += std::norm(dy);
        cyu += dy * std::conj(du);
      }
      const double scale = 1.0 / (static_cast<double>(P) * (P - 1));  // the variance of a mean of P
      vu *= scale;
      vy *= scale;
      cyu *= scale;
      const cd g = ym / um;
      G[m][l] = g;
      const double v = std::norm(g) * (vy / std::norm(ym) + vu / std::norm(um) - 2.0 * (cyu / (ym * std::conj(um))).real());
      var_n[m][l] = std::max(0.0, v);
    }
  }
  RobustEstimate out;
  out.num_periods = P;
  out.num_realisations = M;
  out.period_samples = N;
  out.sample_rate_hz = fs;
  out.S_uu = std::move(suu);
  out.S_yy = std::move(syy);
  out.S_uy = std::move(suy);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t l = 0; l < L; ++l) {
    cd g = 0.0;
    double vn = 0.0;
    for (int m = 0; m < M; ++m) {
      g += G[m][l];
      vn += var_n[m][l];
    }
    g /= M;
    vn /= static_cast<double>(M) * M;
    double total = nan, distortion = nan;
    if (M >= 2) {
      total = 0.0;
      for (int m = 0; m < M; ++m) total += std::norm(G[m][l] - g);
      total /= static_cast<double>(M) * (M - 1);
      distortion = std::max(0.0, total - vn);
    }
    out.f_hz.push_back(lines[l] * fs / N);
    out.H.push_back(g);
    out.noise_var.push_back(vn);
    out.total_var.push_back(total);
    out.distortion_var.push_back(distortion);
  }
  return out;
}

bool RobustOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (period_samples < 4) {
    return fail("RobustOptions::period_samples = " + std::to_string(period_samples) +
                ": give the multisine's period in samples (>= 4; zwidth excite prints it)");
  }
  if (transient_periods < 0) return fail("RobustOptions::transient_periods must be >= 0");
  if (!(fmin_hz >= 0.0)) return fail("RobustOptions::fmin_hz must be >= 0");
  if (!(fmax_hz > fmin_hz)) return fail("RobustOptions::fmax_hz must be > RobustOptions::fmin_hz");
  return true;
}

RobustEstimate EstimateRobust(const std::vector<LocalRecord>& realisations, double fs, const RobustOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  const size_t skip = static_cast<size_t>(o.transient_periods) * static_cast<size_t>(o.period_samples);
  std::vector<LocalRecord> kept;
  kept.reserve(realisations.size());
  for (size_t i = 0; i < realisations.size(); ++i) {
    const LocalRecord& r = realisations[i];
    const size_t whole = r.u.size() / static_cast<size_t>(o.period_samples);
    if (whole < static_cast<size_t>(o.transient_periods) + 2) {
      throw InputError("realisation " + std::to_string(i + 1) + " holds " + std::to_string(whole) +
                       " whole period(s) of " + std::to_string(o.period_samples) +
                       " samples (RobustOptions::period_samples): the robust method needs " +
                       std::to_string(o.transient_periods) + " transient (RobustOptions::transient_periods) + 2 "
                       "steady-state periods; record more periods or drop fewer");
    }
    auto cut = [&](const std::vector<double>& v) {
      return v.size() <= skip ? std::vector<double>{} : std::vector<double>(v.begin() + skip, v.end());
    };
    kept.push_back({cut(r.u), cut(r.y), {}});
  }
  RobustEstimate all = EstimateRobust(kept, fs, o.period_samples);
  RobustEstimate out = all;
  out.f_hz.clear(), out.H.clear(), out.noise_var.clear(), out.distortion_var.clear(), out.total_var.clear();
  out.S_uu.clear(), out.S_yy.clear(), out.S_uy.clear();
  for (size_t l = 0; l < all.f_hz.size(); ++l) {
    if (all.f_hz[l] < o.fmin_hz || all.f_hz[l] > o.fmax_hz) continue;
    out.f_hz.push_back(all.f_hz[l]);
    out.H.push_back(all.H[l]);
    out.noise_var.push_back(all.noise_var[l]);
    out.distortion_var.push_back(all.distortion_var[l]);
    out.total_var.push_back(all.total_var[l]);
    out.S_uu.push_back(all.S_uu[l]);
    out.S_yy.push_back(all.S_yy[l]);
    out.S_uy.push_back(all.S_uy[l]);
  }
  if (out.f_hz.empty()) {
    throw InputError("no excited line in RobustOptions::fmin_hz..RobustOptions::fmax_hz (the excitation's lines "
                     "span " + std::to_string(all.f_hz.front()) + ".." + std::to_string(all.f_hz.back()) + " Hz)");
  }
  return out;
}

CombinedResponse ToCombined(RobustEstimate e) {
  CombinedResponse c;
  c.method = CombinedMethod::kRobust;
  c.num_runs = e.num_realisations;
  FrequencyResponse& r = c.frf;
  r.sample_rate_hz = e.sample_rate_hz;
  r.window_length = e.period_samples;
  const bool scatter = e.num_realisations >= 2;
  r.num_averages = scatter ? e.num_realisations : e.num_periods;
  r.effective_averages = r.num_averages;
  r.bin_correlation = 1.0;
  r.estimator = "robust";
  const size_t L = e.f_hz.size();
  r.H_std.resize(L);
  r.coherence.resize(L);
  for (size_t l = 0; l < L; ++l) {
    const double var = scatter ? e.total_var[l] : e.noise_var[l];
    r.H_std[l] = std::sqrt(var / 2.0);
    // sd = |H| sqrt(1 - g2) / (|g| sqrt(2 n))  <=>  g2 = 1 / (1 + 2 n sd^2 / |H|^2)
    const double a = 2.0 * r.effective_averages * var / 2.0 / std::max(std::norm(e.H[l]), 1e-300);
    r.coherence[l] = 1.0 / (1.0 + a);
  }
  r.f_hz = std::move(e.f_hz);
  r.H = std::move(e.H);
  r.S_uu = std::move(e.S_uu);
  r.S_yy = std::move(e.S_yy);
  r.S_uy = std::move(e.S_uy);
  r.noise_var = std::move(e.noise_var);
  if (scatter) r.distortion_var = std::move(e.distortion_var);
  return c;
}

}  // namespace zwidth::ident
