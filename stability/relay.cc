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

}  // namespace

RelayResult SimulateRelay(const Plant& plant, const RelayOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  plant.Validate();
  StateSpace ss = DiscretizeZoh(plant, o.period_s);
  const int d = o.delay_samples + plant.delay_samples;
  ss.delay_samples = 0;
  const size_t n = static_cast<size_t>(std::llround(o.seconds / o.period_s));
  RelayResult r;
  r.relay_force.resize(n);
  r.damping_force.resize(n);
  r.command.resize(n);
  r.position.resize(n);
  const int ns = static_cast<int>(ss.A.rows());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ns), next(ns);
  double y_prev = 0.0;
  for (size_t k = 0; k < n; ++k) {
    const double y = ss.C.dot(x);
    // The ideal relay -A sign(y(t)) averaged over the sample centred on t = k,
    // with y linear through y_{k-1}, y_k (extrapolated half a sample ahead).
    // A plain sign(y_k) switches up to one sample late, and that lag alone
    // pulls the limit cycle 5-10% below the ultimate frequency at 1 kHz.
    const double ya = 0.5 * (y_prev + y), yb = 1.5 * y - 0.5 * y_prev;
    double relay;
    if ((ya > 0.0) == (yb > 0.0) || ya == yb) {
      relay = (y > 0.0) ? -o.amplitude : o.amplitude;
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
  if (!(ey > 0.0) || !(ef > 0.0)) return r;
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
  if (!(std::abs(X1) > 0.0)) return r;
  r.oscillating = true;
  const double to_hz = 1.0 / (2.0 * std::numbers::pi * o.period_s);
  // The paper's reading: the peak frequency, and |F1|/|X1| there.
  r.K_cr_peak = std::abs(F1) / std::abs(X1);
  r.f_cr_peak_hz = theta * to_hz;
  r.K_cr = r.K_cr_peak;
  r.f_cr_hz = r.f_cr_peak_hz;
  // In a periodic steady state X(k theta)/F(k theta) is the loop's response
  // L(e^{jk theta}) exactly, at every odd harmonic k. The relay locks where
  // only its first harmonic is near -180 deg (the describing-function error:
  // up to 7% in f and 13% in K here, where the phase of 1/(m s^2 + b s) with a
  // delay stays near -180 deg over a wide band). Where L's phase is linear in
  // f over [f, 5f] - the 5th harmonic lies within 10 deg of the line through
  // the 1st and 3rd, as with a rigid body and a delay, not with a resonance in
  // between - the -180 deg crossing is interpolated on that line, with the
  // log-magnitude likewise, and only close to f.
  if (5.0 * theta < std::numbers::pi) {
    std::complex<double> L[3];
    bool ok = true;
    for (int i = 0; i < 3 && ok; ++i) {
      const double th = (2 * i + 1) * theta;
      const std::complex<double> F = Harmonic(r.relay_force, start, th);
      const std::complex<double> X = Harmonic(r.position, start, th);
      ok = std::abs(F) > 0.0 && std::abs(X) > 0.0;
      if (ok) L[i] = X / F;
    }
    if (ok) {
      const double pi = std::numbers::pi;
      double p[3] = {std::arg(L[0]), std::arg(L[1]), std::arg(L[2])};
      for (int i = 1; i < 3; ++i) {  // unwrap: lagging, by less than a turn per step
        while (p[i] > p[i - 1]) p[i] -= 2.0 * pi;
        while (p[i] < p[i - 1] - 2.0 * pi) p[i] += 2.0 * pi;
      }
      const double slope = (p[1] - p[0]) / 2.0;       // per unit of theta/theta_1
      const double p5_line = p[0] + 4.0 * slope;
      double target = -pi;                            // -180 deg (mod 360) nearest p1
      while (target > p[0] + pi) target -= 2.0 * pi;
      while (target < p[0] - pi) target += 2.0 * pi;
      const double x = slope < 0.0 ? (target - p[0]) / slope : 1e9;  // theta*/theta_1 - 1
      if (std::abs(p[2] - p5_line) < 10.0 * pi / 180.0 && std::abs(x) <= 0.25) {
        const double l1 = std::log(std::abs(L[0])), l3 = std::log(std::abs(L[1]));
        r.K_cr = std::exp(-(l1 + x * (l3 - l1) / 2.0));
        r.f_cr_hz = theta * (1.0 + x) * to_hz;
        r.refined = true;
      }
    }
  }
  return r;
}

}  // namespace zwidth::stability
