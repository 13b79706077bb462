#include "ident/joint.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "model/error.h"

namespace zwidth::ident {

std::string ToString(CombinedMethod m) {
  switch (m) {
    case CombinedMethod::kH1: return "H1 = S_uy/S_uu";
    case CombinedMethod::kH2: return "H2 = S_yy/S_yu";
    case CombinedMethod::kJoint: return "joint G = S_ry/S_ru";
    case CombinedMethod::kLpm: return "local polynomial method (LPM)";
    case CombinedMethod::kLrm: return "local rational method (LRM)";
    case CombinedMethod::kRobust: return "robust method (periodic excitation)";
  }
  return "?";
}

RunSpectra EstimateRun(const std::vector<double>& u, const std::vector<double>& y, const std::vector<double>& r,
                       double fs, const WelchOptions& options) {
  RunSpectra s;
  s.uy = EstimateFrequencyResponse(u, y, fs, options);
  if (!r.empty()) {
    if (r.size() != u.size()) throw InputError("the excitation and the input have different lengths");
    s.ru = EstimateFrequencyResponse(r, u, fs, options);
    s.ry = EstimateFrequencyResponse(r, y, fs, options);
  }
  return s;
}

namespace {

// Per-bin estimate and its coherence-based sd from (averaged) spectra.
struct Bin {
  std::complex<double> h;
  double sd = 0, coh = 0, coh_ru = 0, coh_ry = 0;
};

Bin Evaluate(double suu, double syy, std::complex<double> suy, double srr, std::complex<double> sru,
             std::complex<double> sry, double nd, CombinedMethod m) {
  Bin b;
  const double inf = std::numeric_limits<double>::infinity();
  b.coh = (suu > 0 && syy > 0) ? std::norm(suy) / (suu * syy) : 0.0;
  if (m == CombinedMethod::kJoint) {
    b.h = sru != 0.0 ? sry / sru : std::complex<double>(0.0);
    b.coh_ru = (srr > 0 && suu > 0) ? std::norm(sru) / (srr * suu) : 0.0;
    b.coh_ry = (srr > 0 && syy > 0) ? std::norm(sry) / (srr * syy) : 0.0;
    const double see = std::max(0.0, syy - 2.0 * std::real(b.h * std::conj(suy)) + std::norm(b.h) * suu);
    b.sd = std::norm(sru) > 0 ? std::sqrt(srr * see / (2.0 * nd * std::norm(sru))) : inf;
    return b;
  }
  b.h = m == CombinedMethod::kH1 ? suy / suu : syy / std::conj(suy);
  const double c = std::min(b.coh, 1.0);
  b.sd = c > 0.0 ? std::abs(b.h) * std::sqrt((1.0 - c) / (2.0 * nd * c)) : inf;
  return b;
}

// Runs of one estimate: the same rate (0.1 %), segment length and bins, and
// all with an excitation or none.
void CheckRunsAlike(const std::vector<RunSpectra>& runs, bool joint) {
  const FrequencyResponse& first = runs.front().uy;
  for (size_t i = 0; i < runs.size(); ++i) {
    const FrequencyResponse& f = runs[i].uy;
    // Rates measured from time columns differ in the last digits; 0.1 % is a
    // different logger setting.
    if (std::abs(f.sample_rate_hz - first.sample_rate_hz) > 1e-3 * first.sample_rate_hz ||
        f.window_length != first.window_length || f.f_hz.size() != first.f_hz.size()) {
      auto hz = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%.10g", v);
        return std::string(b);
      };
      throw InputError("run " + std::to_string(i + 1) + " has " + hz(f.sample_rate_hz) + " Hz and " +
                       std::to_string(f.window_length) + "-sample segments, run 1 " +
                       hz(first.sample_rate_hz) + " Hz and " + std::to_string(first.window_length) +
                       ": runs of one estimate need the same rate and segment length (whole records: the same length)");
    }
    if (runs[i].ru.has_value() != joint || runs[i].ry.has_value() != joint) {
      throw InputError("run " + std::to_string(i + 1) + (joint ? " lacks" : " has") +
                       " an excitation where run 1 " + (joint ? "has one" : "does not"));
    }
  }
}

// The excitation's spectra summed over runs (joint estimate only).
struct ExcitationSpectra {
  std::vector<double> srr;
  std::vector<std::complex<double>> sru, sry;
};

// r's header (rate, segments, bins, averages) and its spectra S_uu, S_yy, S_uy
// (and the excitation's) as the means over all segments of all runs: each
// run's spectra weighted by its share of the segments.
ExcitationSpectra AverageSpectra(const std::vector<RunSpectra>& runs, bool joint, FrequencyResponse* r) {
  const FrequencyResponse& first = runs.front().uy;
  r->sample_rate_hz = first.sample_rate_hz;
  r->window_length = first.window_length;
  r->bin_correlation = first.bin_correlation;
  r->f_hz = first.f_hz;
  double segments = 0.0;
  for (const RunSpectra& s : runs) {
    r->num_averages += s.uy.num_averages;
    r->effective_averages += s.uy.effective_averages;
    segments += s.uy.num_averages;
  }
  const size_t nb = r->f_hz.size();
  r->S_uu.assign(nb, 0.0);
  r->S_yy.assign(nb, 0.0);
  r->S_uy.assign(nb, 0.0);
  ExcitationSpectra x{std::vector<double>(nb, 0.0), std::vector<std::complex<double>>(nb, 0.0),
                      std::vector<std::complex<double>>(nb, 0.0)};
  for (const RunSpectra& s : runs) {
    const double w = s.uy.num_averages / segments;  // spectra are means over segments
    for (size_t k = 0; k < nb; ++k) {
      r->S_uu[k] += w * s.uy.S_uu[k];
      r->S_yy[k] += w * s.uy.S_yy[k];
      r->S_uy[k] += w * s.uy.S_uy[k];
      if (joint) {
        x.srr[k] += w * s.ru->S_uu[k];
        x.sru[k] += w * s.ru->S_uy[k];
        x.sry[k] += w * s.ry->S_uy[k];
      }
    }
  }
  return x;
}

// H, its std (from the coherence) and the coherences of every bin from the
// averaged spectra.
void EvaluateBins(const ExcitationSpectra& x, bool joint, CombinedResponse* out) {
  FrequencyResponse& r = out->frf;
  const size_t nb = r.f_hz.size();
  const double nd = r.effective_averages;
  r.H.resize(nb);
  r.H_std.resize(nb);
  r.coherence.resize(nb);
  if (joint) {
    out->coherence_ru.resize(nb);
    out->coherence_ry.resize(nb);
  }
  bool any_power = false;
  for (size_t k = 0; k < nb; ++k) {
    if (r.S_uu[k] > 0) any_power = true;
    const Bin b = Evaluate(r.S_uu[k], r.S_yy[k], r.S_uy[k], x.srr[k], x.sru[k], x.sry[k], nd, out->method);
    r.H[k] = b.h;
    r.H_std[k] = b.sd;
    r.coherence[k] = joint ? b.coh_ry : b.coh;
    if (joint) {
      out->coherence_ru[k] = b.coh_ru;
      out->coherence_ry[k] = b.coh_ry;
    }
  }
  if (!any_power) throw InputError("the input has no power in the band: constant input?");
}

// H_std from the scatter of the runs' own estimates about the combined H
// (inf with one run); the runs are the averages.
void StdFromRunScatter(const std::vector<RunSpectra>& runs, bool joint, CombinedResponse* out) {
  FrequencyResponse& r = out->frf;
  const double m = static_cast<double>(runs.size());
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    if (runs.size() < 2) {
      r.H_std[k] = std::numeric_limits<double>::infinity();
      continue;
    }
    double ss = 0.0;
    for (const RunSpectra& s : runs) {
      const Bin b = Evaluate(s.uy.S_uu[k], s.uy.S_yy[k], s.uy.S_uy[k], joint ? s.ru->S_uu[k] : 0.0,
                             joint ? s.ru->S_uy[k] : 0.0, joint ? s.ry->S_uy[k] : 0.0, 1.0, out->method);
      ss += std::norm(b.h - r.H[k]);
    }
    r.H_std[k] = std::sqrt(ss / (2.0 * m * (m - 1.0)));
  }
  // One segment per run: the estimate's averages are the runs; the std is
  // their scatter (fit::Chi2SmallSampleLaw reads "-runs" for its law).
  r.effective_averages = m;
  r.estimator += "-runs";
}

}  // namespace

CombinedResponse CombineRuns(const std::vector<RunSpectra>& runs, Estimator estimator, StdSource std_source) {
  if (runs.empty()) throw InputError("no run to estimate from");
  const bool joint = runs.front().ru.has_value();
  CheckRunsAlike(runs, joint);
  CombinedResponse out;
  out.method = joint ? CombinedMethod::kJoint
                     : (estimator == Estimator::kH1 ? CombinedMethod::kH1 : CombinedMethod::kH2);
  out.num_runs = static_cast<int>(runs.size());
  const ExcitationSpectra x = AverageSpectra(runs, joint, &out.frf);
  EvaluateBins(x, joint, &out);
  out.frf.estimator = joint ? "welch-joint" : (estimator == Estimator::kH1 ? "welch-h1" : "welch-h2");
  if (std_source == StdSource::kRunScatter) StdFromRunScatter(runs, joint, &out);
  return out;
}

}  // namespace zwidth::ident
