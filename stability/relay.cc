#include "stability/relay.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "model/error.h"
#include "model/state_space.h"

#include <unsupported/Eigen/FFT>

namespace zwidth::stability {

bool RelayOptions::IsValid(std::string* why) const {
  auto bad = [&](const char* m) { if (why) *why = m; return false; };
  if (!(std::isfinite(period_s) && period_s > 0)) return bad("--period must be > 0");
  if (delay_samples < 0) return bad("--delay must be >= 0");
  if (!(std::isfinite(damping) && damping >= 0)) return bad("--damping must be >= 0");
  if (!(std::isfinite(amplitude) && amplitude > 0)) return bad("--amplitude must be > 0");
  if (!(std::isfinite(seconds) && seconds > 0)) return bad("--seconds must be > 0");
  if (seconds / period_s > 5e7) return bad("--seconds / --period is over 5e7 samples");
  if (!(settle_fraction >= 0 && settle_fraction <= 0.9)) return bad("settle fraction must be in [0, 0.9]");
  if (seconds * (1.0 - settle_fraction) / period_s < 256) {
    return bad("--seconds too short: the steady part needs at least 256 samples");
  }
  return true;
}

namespace {

// Single-frequency DFT of x[start..] with a Hann window.
std::complex<double> Harmonic(const std::vector<double>& x, size_t start, double theta) {
  const size_t n = x.size() - start;
  std::complex<double> acc = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * i / n);
    acc += w * x[start + i] * std::polar(1.0, -theta * static_cast<double>(i));
  }
  return acc;
}


// One relay run: the output is the ideal relay -A sign(y(t)) averaged over the
// sample centred on t = k + lead, with y linear through y_{k-1} and y_k (a
// plain sign(y_k) switches up to one sample late, which alone pulls the limit
// cycle 5-10% low at 1 kHz). lead > 0 acts on the position extrapolated ahead:
// a phase lead of lead * theta, without the chattering of a negative
// hysteresis; lead < 0 is a lag.
struct Run {
  RelayResult r;
  double theta = 0.0;            // oscillation, rad/sample (spectral peak)
  std::complex<double> L = 0.0;  // X1/F1: the loop's response at theta, exact
  double amplitude = 0.0;        // of the position in steady state
};

Run RunOnce(const StateSpace& ss, int d, const RelayOptions& o, double lead) {
  Run run;
  RelayResult& r = run.r;
  const size_t n = static_cast<size_t>(std::llround(o.seconds / o.period_s));
  r.relay_force.resize(n);
  r.damping_force.resize(n);
  r.command.resize(n);
  r.position.resize(n);
  const int ns = static_cast<int>(ss.A.rows());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ns), next(ns);
  double y_prev = 0.0;
  for (size_t k = 0; k < n; ++k) {
    const double y = ss.C.dot(x);
    // y(t) extrapolated linearly through y_{k-1}, y_k over the sample centred
    // on t = k + lead (lead in samples; 0 for the plain relay).
    const double slope = y - y_prev;
    const double ya = y + slope * (lead - 0.5), yb = y + slope * (lead + 0.5);
    double relay;
    if ((ya > 0.0) == (yb > 0.0) || ya == yb) {
      relay = (0.5 * (ya + yb) > 0.0) ? -o.amplitude : o.amplitude;
    } else {
      const double phi = ya / (ya - yb);  // zero crossing within the sample
      const double positive = ya > 0.0 ? phi : 1.0 - phi;
      relay = -o.amplitude * (2.0 * positive - 1.0);
    }
    const double damp = -o.damping * (y - y_prev) / o.period_s;
    y_prev = y;
    r.position[k] = y;
    r.relay_force[k] = relay;
    r.damping_force[k] = damp;
    const double cmd = relay + damp;
    r.command[k] = cmd;
    const double u = (k >= static_cast<size_t>(d)) ? r.command[k - d] : 0.0;
    next.noalias() = ss.A * x;
    next += ss.B * u;
    x.swap(next);
  }
  const size_t start = static_cast<size_t>(o.settle_fraction * n);
  const size_t m = n - start;
  // Averaged power spectrum of force and position (normalised each), zero-
  // padded, peak refined by golden-section search on the exact DFT power.
  std::vector<double> rf(r.relay_force.begin() + start, r.relay_force.end());
  std::vector<double> ps(r.position.begin() + start, r.position.end());
  auto detrend = [](std::vector<double>& v) {
    double mean = 0.0;
    for (double a : v) mean += a;
    mean /= v.size();
    for (double& a : v) a -= mean;
  };
  detrend(rf);
  detrend(ps);
  // Normalise the two spectra so that neither dominates the average.
  double ef = 0.0, ey = 0.0;
  for (size_t i = 0; i < m; ++i) { ef += rf[i] * rf[i]; ey += ps[i] * ps[i]; }
  if (!(ey > 0.0) || !(ef > 0.0)) return run;
  for (double& v : ps) v *= std::sqrt(ef / ey);
  auto power = [&](double theta) {
    return std::norm(Harmonic(rf, 0, theta)) + std::norm(Harmonic(ps, 0, theta));
  };
  // Coarse peak from a zero-padded FFT of the Hann-windowed signals.
  size_t nfft = 1;
  while (nfft < 4 * m) nfft *= 2;
  std::vector<double> bufa(nfft, 0.0), bufb(nfft, 0.0);
  for (size_t i = 0; i < m; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * i / m);
    bufa[i] = w * rf[i];
    bufb[i] = w * ps[i];
  }
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> sa, sb;
  fft.fwd(sa, bufa);
  fft.fwd(sb, bufb);
  double best_t = 0.0, best_p = -1.0;
  for (size_t k = 1; k < nfft / 2; ++k) {
    const double p = std::norm(sa[k]) + std::norm(sb[k]);
    if (p > best_p) { best_p = p; best_t = 2.0 * std::numbers::pi * k / nfft; }
  }
  const double dtheta = 2.0 * std::numbers::pi / nfft;
  double lo = std::max(dtheta, best_t - dtheta), hi = std::min(std::numbers::pi - dtheta, best_t + dtheta);
  for (int it = 0; it < 60; ++it) {  // golden refinement of the peak
    const double a = lo + (hi - lo) * 0.381966, b = lo + (hi - lo) * 0.618034;
    if (power(a) > power(b)) hi = b; else lo = a;
  }
  const double theta = 0.5 * (lo + hi);
  const std::complex<double> F1 = Harmonic(r.relay_force, start, theta);
  const std::complex<double> X1 = Harmonic(r.position, start, theta);
  if (!(std::abs(X1) > 0.0) || !(std::abs(F1) > 0.0)) return run;
  r.oscillating = true;
  run.theta = theta;
  run.L = X1 / F1;
  double lo_y = r.position[start], hi_y = lo_y;
  for (size_t k = start; k < n; ++k) { lo_y = std::min(lo_y, r.position[k]); hi_y = std::max(hi_y, r.position[k]); }
  run.amplitude = 0.5 * (hi_y - lo_y);
  return run;
}

// Phase of L in (-2 pi, 0]: near the crossover it is close to -pi.
double LagPhase(std::complex<double> L) {
  double p = std::arg(L);
  if (p > 0.0) p -= 2.0 * std::numbers::pi;
  return p;
}

}  // namespace

RelayResult SimulateRelay(const Plant& plant, const RelayOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  plant.Validate();
  StateSpace ss = DiscretizeZoh(plant, o.period_s);
  const int d = o.delay_samples + plant.delay_samples;
  ss.delay_samples = 0;
  const Run base = RunOnce(ss, d, o, 0.0);
  RelayResult r = base.r;
  if (!r.oscillating) return r;
  const double to_hz = 1.0 / (2.0 * std::numbers::pi * o.period_s);
  // The paper's reading: the spectral peak, and |F1|/|X1| there.
  r.K_cr_peak = 1.0 / std::abs(base.L);
  r.f_cr_peak_hz = base.theta * to_hz;
  r.K_cr = r.K_cr_peak;
  r.f_cr_hz = r.f_cr_peak_hz;
  // X1/F1 is the loop's response L exactly at the oscillation frequency, but
  // the relay oscillates only near the -180 deg crossing (the describing-
  // function error: up to 7% in f and 13% in K here, where L's phase stays near
  // -180 deg over a wide band). A relay acting on the position extrapolated
  // ahead (or behind) moves the oscillation while X1/F1 stays exact, so runs
  // with a growing lead (or lag: 0.5 deg, times 1.5 up to 43 deg) bracket the crossing
  // between two exact values of L, interpolated linearly in f (phase and
  // log-magnitude). A run that jumps to another limit cycle (f off by 50%,
  // a vibration mode near B_t) stops the search: the paper's reading stays.
  const double target = -std::numbers::pi;
  double p_prev = LagPhase(base.L);
  if (p_prev == target) { r.refined = true; return r; }
  const double dir = p_prev > target ? 1.0 : -1.0;  // short of -180 deg: lead; past it: lag
  double prev_theta = base.theta;       // the last run on this side of -180 deg
  std::complex<double> prev_L = base.L;
  double phi = 0.5 * std::numbers::pi / 180.0;
  for (int attempt = 0; attempt < 12; ++attempt, phi *= 1.5) {
    const Run run = RunOnce(ss, d, o, dir * phi / base.theta);
    if (!run.r.oscillating || std::abs(run.theta / base.theta - 1.0) > 0.5) break;  // another limit cycle
    const double p = LagPhase(run.L);
    if ((p - target) * (p_prev - target) <= 0.0) {
      const double t = (target - p_prev) / (p - p_prev);
      const double theta = prev_theta + t * (run.theta - prev_theta);
      const double logmag = std::log(std::abs(prev_L)) + t * (std::log(std::abs(run.L)) - std::log(std::abs(prev_L)));
      r.K_cr = std::exp(-logmag);
      r.f_cr_hz = theta * to_hz;
      r.refined = true;
      break;
    }
    if (std::abs(p - p_prev) < 1e-9) continue;  // locked on the same period: no new point
    prev_theta = run.theta;
    prev_L = run.L;
    p_prev = p;
  }
  return r;
}

}  // namespace zwidth::stability
