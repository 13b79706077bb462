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

}  // namespace zwidth::ident
