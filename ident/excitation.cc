#include "ident/excitation.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "ident/fft.h"
#include "model/c_locale.h"
#include "model/error.h"
#include "model/simulate.h"

namespace zwidth::ident {
namespace {

double Rms(const std::vector<double>& x) {
  double s = 0;
  for (double v : x) s += v * v;
  return x.empty() ? 0.0 : std::sqrt(s / x.size());
}

void ScaleTo(std::vector<double>* x, double rms) {
  const double r = Rms(*x);
  if (r > 0) for (double& v : *x) v *= rms / r;
}

}  // namespace

std::string ToString(ExcitationKind k) {
  switch (k) {
    case ExcitationKind::kNoise: return "noise";
    case ExcitationKind::kMultisine: return "multisine";
    case ExcitationKind::kChirp: return "chirp";
  }
  return "?";
}

bool FromString(const std::string& s, ExcitationKind* k) {
  if (s == "noise") *k = ExcitationKind::kNoise;
  else if (s == "multisine") *k = ExcitationKind::kMultisine;
  else if (s == "chirp") *k = ExcitationKind::kChirp;
  else return false;
  return true;
}

bool ExcitationOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (!(sample_rate_hz > 0.0 && std::isfinite(sample_rate_hz))) return bad("ExcitationOptions::sample_rate_hz must be finite and > 0");
  if (!(seconds > 0.0 && std::isfinite(seconds))) return bad("ExcitationOptions::seconds must be finite and > 0");
  // `excite` peaks at ~58 bytes a sample (the whole record's spectrum; 2e7 samples: 1.15 GB, 16 s
  // here): 1e7 keeps it near 600 MB (2.8 h at 1 kHz); 1e8 took ~5.8 GB from one flag.
  if (seconds * sample_rate_hz > 1e7) return bad("ExcitationOptions::seconds x ExcitationOptions::sample_rate_hz is over 1e7 samples");
  if (seconds * sample_rate_hz < 16) return bad("ExcitationOptions::seconds x ExcitationOptions::sample_rate_hz gives fewer than 16 samples");
  if (!(rms > 0.0 && std::isfinite(rms))) return bad("ExcitationOptions::rms must be finite and > 0");
  if (rms > model::kMaxSignalRms) {  // 1e308 was scaled to inf and written as "rms=inf"
    return bad("ExcitationOptions::rms = " + FormatG(rms) + " is above 1e12 (input units)");
  }
  if (!(fmin_hz >= 0.0 && std::isfinite(fmin_hz))) return bad("ExcitationOptions::fmin_hz must be finite and >= 0");
  if (kind == ExcitationKind::kChirp && !(fmin_hz > 0.0)) return bad("ExcitationOptions::fmin_hz must be > 0 for a logarithmic chirp");
  if (!(fmax_hz > fmin_hz)) return bad("ExcitationOptions::fmax_hz must be > ExcitationOptions::fmin_hz");
  if (!(fmax_hz < 0.5 * sample_rate_hz)) {
    return bad("ExcitationOptions::fmax_hz = " + std::to_string(fmax_hz) + " Hz must be below the Nyquist frequency " +
               std::to_string(0.5 * sample_rate_hz) + " Hz");
  }
  return true;
}

double CrestFactor(const std::vector<double>& x) {
  double peak = 0;
  for (double v : x) peak = std::max(peak, std::abs(v));
  const double r = Rms(x);
  return r > 0 ? peak / r : 0.0;
}

double BandPowerFraction(const std::vector<double>& x, double fs, double fmin, double fmax) {
  const auto X = ForwardReal(x);
  const double df = fs / x.size();
  double in = 0, all = 0;
  for (size_t k = 0; k < X.size(); ++k) {
    const double p = std::norm(X[k]);
    all += p;
    const double f = k * df;
    if (f >= fmin - 1e-9 * df && f <= fmax + 1e-9 * df) in += p;
  }
  return all > 0 ? in / all : 0.0;
}

Excitation MakeExcitation(const ExcitationOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("excitation: " + why);
  Excitation e;
  e.sample_rate_hz = o.sample_rate_hz;
  const double fs = o.sample_rate_hz;
  int n = static_cast<int>(std::llround(o.seconds * fs));
  e.period_samples = n;
  if (o.kind == ExcitationKind::kNoise) {
    std::mt19937_64 rng(o.seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<double> w(n);
    for (double& v : w) v = g(rng);
    auto X = ForwardReal(w);
    const double df = fs / n;
    for (size_t k = 0; k < X.size(); ++k) {
      const double f = k * df;
      if (f < o.fmin_hz - 1e-9 * df || f > o.fmax_hz + 1e-9 * df || k == 0) X[k] = 0.0;
    }
    e.signal = InverseReal(X, n);
  } else if (o.kind == ExcitationKind::kMultisine) {
    // Line spacing f0 = fmin (or 1/seconds when fmin is 0): a period of
    // P = fs / f0 samples, repeated a whole number of times.
    const double f0_wanted = std::max(o.fmin_hz, 1.0 / o.seconds);
    const int P = std::min(n, static_cast<int>(std::llround(fs / f0_wanted)));
    const int periods = std::max(1, n / P);
    const double f0 = fs / P;
    const int k_lo = std::max(1, static_cast<int>(std::ceil(o.fmin_hz / f0 - 1e-9)));
    const int k_hi = std::min(P / 2 - (P % 2 == 0 ? 1 : 0), static_cast<int>(std::floor(o.fmax_hz / f0 + 1e-9)));
    const int K = k_hi - k_lo + 1;
    if (K < 1) {
      throw InputError("excitation: no multisine line k f0 (f0 = " + std::to_string(f0) + " Hz) in [fmin, fmax]; widen the band");
    }
    // Schroeder (1970): phi_k = -pi k (k - 1) / K for the K equal lines; or
    // random phases, uniform in [0, 2 pi), from the seed.
    std::vector<std::complex<double>> X(P / 2 + 1, 0.0);
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> uniform(0.0, 2.0 * std::numbers::pi);
    for (int i = 1; i <= K; ++i) {
      const double phi = o.random_phases ? uniform(rng) : -std::numbers::pi * i * (i - 1.0) / K;
      X[k_lo + i - 1] = std::polar(0.5, phi);
    }
    const std::vector<double> period = InverseReal(X, P);
    e.signal.reserve(static_cast<size_t>(periods) * P);
    for (int r = 0; r < periods; ++r) e.signal.insert(e.signal.end(), period.begin(), period.end());
    e.period_samples = P;
    e.num_periods = periods;
    e.num_lines = K;
    e.line_spacing_hz = f0;
  } else {
    const double T = n / fs, ratio = o.fmax_hz / o.fmin_hz, L = std::log(ratio);
    e.signal.resize(n);
    for (int i = 0; i < n; ++i) {
      const double t = i / fs;
      e.signal[i] = std::sin(2 * std::numbers::pi * o.fmin_hz * T / L * (std::exp(L * t / T) - 1.0));
    }
  }
  ScaleTo(&e.signal, o.rms);
  e.rms = Rms(e.signal);
  e.crest_factor = CrestFactor(e.signal);
  e.band_power_fraction = BandPowerFraction(e.signal, fs, o.fmin_hz, o.fmax_hz);
  return e;
}

}  // namespace zwidth::ident
