#include "stability/relay.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#include "model/cancel.h"
#include "model/error.h"
#include "model/simulate.h"
#include "model/nonlinear_simulate.h"
#include "model/state_space.h"
#include "stability/hand.h"
#include "stability/velocity_filter_internal.h"
#include "stability/zwidth.h"

#include <unsupported/Eigen/FFT>

namespace zwidth::stability {

bool RelayOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = "RelayOptions::" + m; return false; };
  if (!(std::isfinite(period_s) && period_s > 0)) return bad("period_s must be finite and > 0");
  if (delay_samples < 0) return bad("delay_samples must be >= 0");
  if (!(std::isfinite(damping) && damping >= 0)) return bad("damping must be finite and >= 0");
  // The wall's and the hand's bound (kMaxLoopValue): B = 1e300 was simulated and reported.
  if (damping > kMaxLoopValue) return bad("damping must lie in [0, 1e12]");
  if (!(std::isfinite(amplitude) && amplitude > 0)) return bad("amplitude must be finite and > 0");
  if (!(std::isfinite(seconds) && seconds > 0)) return bad("seconds must be finite and > 0");
  if (seconds / period_s > 5e7) return bad("seconds / period_s is over 5e7 samples: simulate less");
  if (!(settle_fraction >= 0 && settle_fraction <= 0.9)) return bad("settle_fraction must be in [0, 0.9]");
  if (seconds * (1.0 - settle_fraction) / period_s < 256) {
    return bad("seconds too short: the steady part, seconds x (1 - settle_fraction), needs at least 256 samples");
  }
  std::string loop_why;
  if (!loop.IsValid(&loop_why)) return bad("loop." + loop_why);
  if (!friction.IsValid(&loop_why)) return bad("friction." + loop_why);
  if (!actuator.IsValid(&loop_why)) return bad("actuator." + loop_why);
  if (!(std::isfinite(encoder_step) && encoder_step >= 0)) return bad("encoder_step must be finite and >= 0");
  if (std::string p = model::EncoderStepProblem(encoder_step, "encoder_step"); !p.empty()) return bad(p);
  return true;
}

namespace {
constexpr std::pair<RelayStatus, const char*> kStatusNames[] = {
    {RelayStatus::kNotRun, "not_run"},         {RelayStatus::kRefined, "refined"},
    {RelayStatus::kPeakReading, "peak_reading"}, {RelayStatus::kBelowBand, "below_band"},
    {RelayStatus::kDiverged, "diverged"},       {RelayStatus::kNoOscillation, "no_oscillation"},
};
}  // namespace

std::string ToString(RelayStatus s) {
  for (const auto& [v, name] : kStatusNames) {
    if (v == s) return name;
  }
  return "unknown";
}

RelayStatus RelayStatusFromString(const std::string& s) {
  for (const auto& [v, name] : kStatusNames) {
    if (s == name) return v;
  }
  throw InputError("relay status '" + s + "': expected refined, peak_reading, below_band, diverged, no_oscillation "
                   "or not_run");
}

namespace {

constexpr double kResonatorQ = 2.0;  // of each of the two resonators
constexpr int kMaxScanRuns = 40;       // filtered runs of the scan
constexpr int kMaxRefineRuns = 10;     // filtered runs per crossing or dip
constexpr double kDipDeg = 10.0;       // a dip of the phase this close to -180 deg is probed

// Calls term(i, t, a) for i in [0, n) with a = w_i x_i e^{-j theta t}, t = i -
// origin. The phasor advances by one complex product per sample and is reset
// from std::polar every 256 samples (rounding stays near 1e-14).
template <class Term>
void WindowedTerms(const double* x, const std::vector<double>& w, double theta, double origin, Term term) {
  const size_t n = w.size();
  const std::complex<double> step = std::polar(1.0, -theta);
  std::complex<double> e = 1.0;
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) - origin;
    if ((i & 255u) == 0) e = std::polar(1.0, -theta * t);
    term(t, (w[i] * x[i]) * e);
    e *= step;
  }
}

// Single-frequency DFT of x[0..n) times a window w[0..n): sum w_i x_i e^{-j theta i}.
std::complex<double> Harmonic(const double* x, const std::vector<double>& w, double theta) {
  std::complex<double> acc = 0.0;
  WindowedTerms(x, w, theta, 0.0, [&](double, std::complex<double> a) { acc += a; });
  return acc;
}

// The 4-term Blackman-Harris window (sidelobes 92 dB down): the drift of the
// position and the square wave's other harmonics leak far less than with Hann.
std::vector<double> BlackmanHarris(size_t n) {
  std::vector<double> w(n);
  const double k = 2.0 * std::numbers::pi / static_cast<double>(n);
  for (size_t i = 0; i < n; ++i) {
    const double x = k * static_cast<double>(i);
    w[i] = 0.35875 - 0.48829 * std::cos(x) + 0.14128 * std::cos(2 * x) - 0.01168 * std::cos(3 * x);
  }
  return w;
}

// |X(theta)|^2 of a windowed signal and its first two derivatives in theta,
// in one pass (the index centred on the window keeps the sums well scaled).
struct PowerDerivatives {
  double d1 = 0.0, d2 = 0.0;
};
PowerDerivatives Power(const double* x, const std::vector<double>& w, double theta) {
  std::complex<double> X = 0.0, X1 = 0.0, X2 = 0.0;
  WindowedTerms(x, w, theta, 0.5 * static_cast<double>(w.size()), [&](double t, std::complex<double> a) {
    X += a;
    X1 += t * a;
    X2 += (t * t) * a;
  });
  // X' = -j X1, X'' = -X2.
  const std::complex<double> dX(X1.imag(), -X1.real());
  PowerDerivatives p;
  p.d1 = 2.0 * std::real(std::conj(X) * dX);
  p.d2 = 2.0 * (std::norm(dX) - std::real(std::conj(X) * X2));
  return p;
}

// The windows of a relay estimate, built once for all its runs (same length).
class WindowCache {
 public:
  const std::vector<double>& Full(size_t m) {
    if (full_.size() != m) full_ = BlackmanHarris(m);
    return full_;
  }
  const std::vector<double>& Half(size_t m) {
    if (half_.size() != m / 2) half_ = BlackmanHarris(m / 2);
    return half_;
  }

 private:
  std::vector<double> full_, half_;
};

// A second-order resonator (band-pass, RBJ form): unit gain and zero phase at
// its centre w0 [rad/sample], a phase lead below it and a lag above it (up to
// +-90 deg), and a roll-off of 1/(q x) at x times w0 or w0 / x.
struct Resonator {
  double b0 = 1.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
  double x1 = 0.0, x2 = 0.0, y1 = 0.0, y2 = 0.0;
  static Resonator At(double w0, double q) {
    Resonator r;
    const double alpha = std::sin(w0) / (2.0 * q), a0 = 1.0 + alpha;
    r.b0 = alpha / a0;
    r.b2 = -alpha / a0;
    r.a1 = -2.0 * std::cos(w0) / a0;
    r.a2 = (1.0 - alpha) / a0;
    return r;
  }
  double Step(double x) {
    const double y = b0 * x + b2 * x2 - a1 * y1 - a2 * y2;
    x2 = x1; x1 = x; y2 = y1; y1 = y;
    return y;
  }
};

// The ideal relay -A sign(s(t)) averaged over the sample centred on t = k,
// with s linear through s_{k-1} and s_k (a plain sign(s_k) switches up to one
// sample late, which alone pulls the limit cycle 5-10% low at 1 kHz).
double RelayOutput(double s_prev, double s, double amplitude) {
  const double slope = s - s_prev;
  const double ya = s - 0.5 * slope, yb = s + 0.5 * slope;
  if ((ya > 0.0) == (yb > 0.0) || ya == yb) return (0.5 * (ya + yb) > 0.0) ? -amplitude : amplitude;
  const double phi = ya / (ya - yb);  // zero crossing within the sample
  const double positive = ya > 0.0 ? phi : 1.0 - phi;
  return -amplitude * (2.0 * positive - 1.0);
}

// The time loop of one relay run, filling r's traces. s is the position, or
// (centre > 0) the position through two resonators at that centre: they steer
// the oscillation towards the centre and keep the square wave's harmonics
// (which can lock the cycle onto a vibration mode) out of the switching. The
// damping force is -B F(z)(1 - z^-1)/T y; relay plus damping reach the plant d
// samples later.
void SimulateLoop(const model::StateSpace& ss, int d, const RelayOptions& o, double centre, RelayResult* r) {
  const size_t n = static_cast<size_t>(std::llround(o.seconds / o.period_s));
  r->relay_force.resize(n);
  r->damping_force.resize(n);
  r->command.resize(n);
  r->position.resize(n);
  const int ns = static_cast<int>(ss.A.rows());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ns), next(ns);
  // A continuous realisation (period_s 0, RelayPlant): the nonlinear device.
  std::optional<model::StickSlipPlant> device;
  if (ss.period_s == 0.0) device.emplace(ss, o.friction, o.period_s);
  const bool filtered = centre > 0.0;
  Resonator f1, f2;
  if (filtered) f1 = f2 = Resonator::At(centre, kResonatorQ);
  internal::VelocityFilter velocity(o.loop);
  double y_prev = 0.0, s_prev = 0.0;
  for (size_t k = 0; k < n; ++k) {
    if ((k & 1023) == 0) PollCancel();  // model/cancel.h: a host's Ctrl-C
    double y = device ? device->position() : ss.C.dot(x);
    if (o.encoder_step > 0.0) y = o.encoder_step * std::round(y / o.encoder_step);
    const double s = filtered ? f2.Step(f1.Step(y)) : y;
    const double relay = RelayOutput(s_prev, s, o.amplitude);
    s_prev = s;
    const double damp = -o.damping * velocity.Step((y - y_prev) / o.period_s);
    y_prev = y;
    r->position[k] = y;
    r->relay_force[k] = relay;
    r->damping_force[k] = damp;
    r->command[k] = relay + damp;
    const double u = o.actuator.Apply((k >= static_cast<size_t>(d)) ? r->command[k - d] : 0.0);
    if (device) {
      device->Step(u);
      continue;
    }
    next.noalias() = ss.A * x;
    next += ss.B * u;
    x.swap(next);
  }
}

// Diverging (the loop is unstable without the relay, past B_max_from_zero):
// the peak grows by the same factor, over 1.2, from each quarter of the steady
// part [start, end) to the next (exponential growth; a cycle still building up
// or changing over grows by changing factors), or overflows.
bool Diverges(const std::vector<double>& position, size_t start) {
  const size_t m = position.size() - start;
  auto peak = [&](size_t q) {
    double v = 0.0;
    for (size_t k = start + q * m / 4; k < start + (q + 1) * m / 4; ++k) {
      if (!std::isfinite(position[k])) return std::numeric_limits<double>::infinity();
      v = std::max(v, std::abs(position[k]));
    }
    return v;
  };
  const double q0 = peak(0), q1 = peak(1), q2 = peak(2), q3 = peak(3);
  const double g1 = q1 / q0, g2 = q2 / q1, g3 = q3 / q2;
  const double g_lo = std::min({g1, g2, g3}), g_hi = std::max({g1, g2, g3});
  return !std::isfinite(q3) || (g_lo > 1.2 && g_hi < 1.25 * g_lo);
}

// The peak of the averaged power spectra of force and position (each
// normalised, mean removed), as the paper reads the oscillation frequency
// [rad/sample]; NaN when either signal is flat.
double SpectralPeak(std::vector<double> rf, std::vector<double> ps, const std::vector<double>& window) {
  const size_t m = rf.size();
  auto detrend = [](std::vector<double>& v) {
    double mean = 0.0;
    for (double a : v) mean += a;
    mean /= static_cast<double>(v.size());
    for (double& a : v) a -= mean;
  };
  detrend(rf);
  detrend(ps);
  // Normalise the two spectra so that neither dominates the average.
  double ef = 0.0, ey = 0.0;
  for (size_t i = 0; i < m; ++i) { ef += rf[i] * rf[i]; ey += ps[i] * ps[i]; }
  if (!(ey > 0.0) || !(ef > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  for (double& v : ps) v *= std::sqrt(ef / ey);
  // Coarse peak from a zero-padded FFT of the windowed signals.
  size_t nfft = 1;
  while (nfft < m) nfft *= 2;
  std::vector<double> bufa(nfft, 0.0), bufb(nfft, 0.0);
  for (size_t i = 0; i < m; ++i) {
    bufa[i] = window[i] * rf[i];
    bufb[i] = window[i] * ps[i];
  }
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> sa, sb;
  fft.fwd(sa, bufa);
  fft.fwd(sb, bufb);
  size_t best_k = 1;
  double best_p = -1.0;
  for (size_t k = 1; k < nfft / 2; ++k) {
    const double p = std::norm(sa[k]) + std::norm(sb[k]);
    if (p > best_p) { best_p = p; best_k = k; }
  }
  // Newton on the derivative of the exact DFT power, kept inside the bins
  // either side of the coarse peak (bisection on its sign where Newton would
  // leave them), to 1e-10 rad/sample.
  const double dtheta = 2.0 * std::numbers::pi / static_cast<double>(nfft);
  double lo = std::max(1e-9, (static_cast<double>(best_k) - 1.0) * dtheta);
  double hi = std::min(std::numbers::pi - 1e-9, (static_cast<double>(best_k) + 1.0) * dtheta);
  double theta = static_cast<double>(best_k) * dtheta;
  for (int it = 0; it < 40 && hi - lo > 1e-10; ++it) {
    const PowerDerivatives pa = Power(rf.data(), window, theta), pb = Power(ps.data(), window, theta);
    const double d1 = pa.d1 + pb.d1, d2 = pa.d2 + pb.d2;
    if (d1 > 0.0) lo = theta; else hi = theta;
    const double step = d2 < 0.0 ? -d1 / d2 : 0.0;
    const double next = theta + step;
    if (d2 < 0.0 && next > lo && next < hi) {
      theta = next;
      if (std::abs(step) < 1e-10) break;
    } else {
      theta = 0.5 * (lo + hi);
    }
  }
  return theta;
}

// One relay run (plain: centre = 0; steered: the resonators' centre [rad/sample]).
struct Run {
  RelayResult r;                 // traces; status kDiverged, kNoOscillation or kPeakReading (oscillating)
  double theta = 0.0;            // oscillation, rad/sample (spectral peak)
  std::complex<double> L = 0.0;  // X1/F1: the loop's response at theta, exact
  double unsettled = 0.0;        // |L(first half) - L(second half)| / |L| of the steady part
};

Run RunOnce(const model::StateSpace& ss, int d, const RelayOptions& o, double centre, WindowCache& windows) {
  Run run;
  RelayResult& r = run.r;
  r.status = RelayStatus::kNoOscillation;
  SimulateLoop(ss, d, o, centre, &r);
  const size_t n = r.position.size();
  const size_t start = static_cast<size_t>(o.settle_fraction * static_cast<double>(n));
  const size_t m = n - start;
  if (Diverges(r.position, start)) {
    r.status = RelayStatus::kDiverged;
    return run;
  }
  const std::vector<double>& window = windows.Full(m);
  const double theta = SpectralPeak(std::vector<double>(r.relay_force.begin() + start, r.relay_force.end()),
                                    std::vector<double>(r.position.begin() + start, r.position.end()), window);
  if (!std::isfinite(theta)) return run;
  const std::complex<double> F1 = Harmonic(r.relay_force.data() + start, window, theta);
  const std::complex<double> X1 = Harmonic(r.position.data() + start, window, theta);
  if (!(std::abs(X1) > 0.0) || !(std::abs(F1) > 0.0)) return run;
  r.status = RelayStatus::kPeakReading;
  run.theta = theta;
  run.L = X1 / F1;
  // Still settling (a slow transient, e.g. near B_max): the two halves disagree.
  const std::vector<double>& half = windows.Half(m);
  const size_t mid = start + m - half.size();
  const std::complex<double> La = Harmonic(r.position.data() + start, half, theta) /
                                  Harmonic(r.relay_force.data() + start, half, theta);
  const std::complex<double> Lb = Harmonic(r.position.data() + mid, half, theta) /
                                  Harmonic(r.relay_force.data() + mid, half, theta);
  run.unsettled = std::abs(La - Lb) / std::abs(run.L);
  return run;
}

// The phase of L minus -180 deg, wrapped to [-pi, pi].
double PhaseError(std::complex<double> L) {
  return std::remainder(std::arg(L) + std::numbers::pi, 2.0 * std::numbers::pi);
}

// One filtered run: its centre, its oscillation theta [rad/sample], L there
// and g = PhaseError(L).
struct Point {
  double centre, theta, g;
  std::complex<double> L;
  double unsettled;
};

// The steered runs of one relay estimate and their search for the -180 deg
// crossings of L. X1/F1 is the loop's response L exactly at the oscillation
// frequency, but the relay oscillates only near a -180 deg crossing (the
// describing-function error: up to 7% in f and 13% in K here, where L's phase
// stays near -180 deg over a wide band), and near B_t it can lock onto a
// vibration mode's cycle, which is not the critical one. Runs with the
// resonators in the relay path oscillate near a chosen centre, each measuring
// L exactly at its own oscillation. A scan of centres (x sqrt 2, from 20
// cycles in the steady part to 0.9 Nyquist; halved where the phase moves over
// 45 deg or |L| over 2x between runs; dips towards -180 deg probed) finds the
// -180 deg crossings; the Illinois method on the centre narrows each bracket
// to 1e-4 in f, where K and f are interpolated linearly in f (phase and log-
// magnitude). K_cr is the smallest K over the crossings. A crossing below the
// scan's lowest frequency is reported (kBelowBand), not guessed.
class SteeredSearch {
 public:
  SteeredSearch(const model::StateSpace& ss, int d, const RelayOptions& o, WindowCache& windows)
      : ss_(ss), d_(d), o_(o), windows_(windows) {}
  int runs() const { return runs_; }

  // The scan from theta_min to theta_max [rad/sample], sorted by theta, with
  // its steps split where L moves fast.
  std::vector<Point> Scan(double theta_min, double theta_max);
  // Adds runs past -180 deg found at dips of the phase towards it.
  void ProbeDips(std::vector<Point>& scan);
  // The smallest K over the refined -180 deg crossings of the scan, into r
  // (K_cr, f_cr_hz, unsettled, uncertainty); false when the scan has none.
  bool RefineCrossings(const std::vector<Point>& scan, double to_hz, RelayResult& r);

 private:
  std::optional<Point> Measure(double centre) {
    ++runs_;
    const Run run = RunOnce(ss_, d_, o_, centre, windows_);
    // Not steered (another cycle, or a drift, took over): no use for the search.
    if (!run.r.oscillating() || std::abs(std::log(run.theta / centre)) > std::log(2.0)) return std::nullopt;
    return Point{centre, run.theta, PhaseError(run.L), run.L, run.unsettled};
  }
  static bool ByTheta(const Point& a, const Point& b) { return a.theta < b.theta; }

  const model::StateSpace& ss_;
  int d_;
  const RelayOptions& o_;
  WindowCache& windows_;
  int runs_ = 0;
};

std::vector<Point> SteeredSearch::Scan(double theta_min, double theta_max) {
  std::vector<Point> scan;
  for (double c = theta_min; c < theta_max && runs_ < kMaxScanRuns; c *= std::numbers::sqrt2) {
    if (auto p = Measure(c)) scan.push_back(*p);
  }
  std::sort(scan.begin(), scan.end(), ByTheta);
  for (size_t i = 0; i + 1 < scan.size() && runs_ < kMaxScanRuns;) {
    const Point& a = scan[i];
    const Point& b = scan[i + 1];
    const double jump = std::abs(std::remainder(b.g - a.g, 2.0 * std::numbers::pi));
    const double gain = std::abs(std::log(std::abs(b.L) / std::abs(a.L)));
    if ((jump <= std::numbers::pi / 4 && gain <= std::log(2.0)) ||
        std::abs(std::log(b.centre / a.centre)) < std::log(1.02)) {
      ++i;
      continue;
    }
    const auto p = Measure(std::sqrt(a.centre * b.centre));
    if (p && p->theta > a.theta && p->theta < b.theta) {
      scan.insert(scan.begin() + static_cast<std::ptrdiff_t>(i) + 1, *p);
    } else {
      ++i;  // another cycle took over: leave this pair as it is
    }
  }
  return scan;
}

// A dip: the phase comes within 10 deg of -180 deg and turns back between two
// scan runs. Successive parabolic steps towards its extremum look for a run
// on the other side, which makes two brackets of a close pair of crossings.
void SteeredSearch::ProbeDips(std::vector<Point>& scan) {
  for (size_t i = 1; i + 1 < scan.size(); ++i) {
    const double sgn = scan[i].g > 0.0 ? 1.0 : -1.0;
    auto depth = [&](const Point& q) { return sgn * q.g; };  // > 0 on the dip's side
    if (!(depth(scan[i]) < kDipDeg * std::numbers::pi / 180.0 && depth(scan[i - 1]) > depth(scan[i]) &&
          depth(scan[i + 1]) > depth(scan[i]))) {
      continue;
    }
    Point a = scan[i - 1], b = scan[i], c = scan[i + 1];
    for (int it = 0; it < kMaxRefineRuns; ++it) {
      // Vertex of the parabola through (log theta, depth) of a, b, c.
      const double xa = std::log(a.theta), xb = std::log(b.theta), xc = std::log(c.theta);
      const double da = depth(a), db = depth(b), dc = depth(c);
      const double num = (xb - xa) * (xb - xa) * (db - dc) - (xb - xc) * (xb - xc) * (db - da);
      const double den = (xb - xa) * (db - dc) - (xb - xc) * (db - da);
      if (!(std::abs(den) > 0.0)) break;
      const double xv = std::clamp(xb - 0.5 * num / den, xa + 0.01 * (xc - xa), xc - 0.01 * (xc - xa));
      const auto q = Measure(std::exp(xv) * b.centre / b.theta);
      if (!q || !(q->theta > a.theta && q->theta < c.theta) || std::abs(q->theta / b.theta - 1.0) < 1e-5) break;
      if (depth(*q) <= 0.0) {  // through -180 deg: two crossings
        scan.insert(std::upper_bound(scan.begin(), scan.end(), *q, ByTheta), *q);
        break;
      }
      if (depth(*q) < db) {
        (q->theta < b.theta ? c : a) = b;
        b = *q;
      } else {
        (q->theta < b.theta ? a : c) = *q;
      }
    }
  }
}

// K and f [rad/sample] at the crossing, interpolated linearly in f between
// two runs on either side (phase error and log |L|).
double KAtCrossing(const Point& lo, const Point& hi, double* f) {
  const double t = lo.g == hi.g ? 0.0 : lo.g / (lo.g - hi.g);
  *f = lo.theta + t * (hi.theta - lo.theta);
  return std::exp(-(std::log(std::abs(lo.L)) + t * (std::log(std::abs(hi.L)) - std::log(std::abs(lo.L)))));
}

// A -180 deg crossing: g changes sign without a jump of 2 pi (that is a 0 deg
// one). The scan split brackets where |L| changed by over 2x, so a bracket
// whose ends both lie over twice the best K found is taken not to hold the
// smallest and skipped; the likeliest are refined first (Illinois on the
// centre: the end kept twice running has its phase error halved).
bool SteeredSearch::RefineCrossings(const std::vector<Point>& scan, double to_hz, RelayResult& r) {
  std::vector<std::pair<double, size_t>> brackets;  // (interpolated K, index of the lower end)
  for (size_t i = 0; i + 1 < scan.size(); ++i) {
    const Point& lo = scan[i];
    const Point& hi = scan[i + 1];
    if ((lo.g > 0.0) == (hi.g > 0.0) || std::abs(hi.g - lo.g) >= std::numbers::pi) continue;
    double f;
    brackets.emplace_back(KAtCrossing(lo, hi, &f), i);
  }
  std::sort(brackets.begin(), brackets.end());
  bool found = false;
  for (const auto& [k_guess, i] : brackets) {
    Point lo = scan[i], hi = scan[i + 1];
    if (found && 0.5 * std::min(1.0 / std::abs(lo.L), 1.0 / std::abs(hi.L)) > r.K_cr) continue;
    // Slopes of the phase and of log |L| against log f over the scan's bracket.
    const double span = std::log(hi.theta / lo.theta);
    const double slope_g = std::abs(hi.g - lo.g) / span;
    const double slope_m = std::abs(std::log(std::abs(hi.L) / std::abs(lo.L))) / span;
    double g_lo = lo.g, g_hi = hi.g;
    int kept = 0;  // +1: lo kept last time, -1: hi kept
    for (int it = 0; it < kMaxRefineRuns && hi.theta - lo.theta > 1e-4 * hi.theta; ++it) {
      const auto p = Measure(lo.centre + (hi.centre - lo.centre) * g_lo / (g_lo - g_hi));
      if (!p || !(p->theta > lo.theta && p->theta < hi.theta) || std::abs(p->g) >= std::numbers::pi / 2) {
        break;  // no narrower bracket
      }
      if (std::abs(p->g) < 1e-7) {  // on the crossing
        lo = hi = *p;
        break;
      }
      if ((p->g > 0.0) == (lo.g > 0.0)) {
        lo = *p;
        g_lo = p->g;
        if (kept == -1) g_hi *= 0.5;
        kept = -1;
      } else {
        hi = *p;
        g_hi = p->g;
        if (kept == 1) g_lo *= 0.5;
        kept = 1;
      }
    }
    double f;
    const double K = KAtCrossing(lo, hi, &f);
    if (!found || K < r.K_cr) {
      r.K_cr = K;
      r.f_cr_hz = f * to_hz;
      r.unsettled = std::max(lo.unsettled, hi.unsettled);
      // L is good to about `unsettled` (relative, so in phase too, radians):
      // that moves the crossing by unsettled / slope_g in log f, and K by
      // that times slope_m, plus unsettled itself.
      // A bracket left wide (the oscillation locked to a whole number of
      // samples per period) adds up to half its spread in K and f.
      const double dlogf = r.unsettled / slope_g;
      r.uncertainty = std::max({dlogf, r.unsettled + slope_m * dlogf,
                                0.5 * std::abs(std::log(std::abs(hi.L) / std::abs(lo.L))),
                                0.5 * std::log(hi.theta / lo.theta)});
    }
    found = true;
  }
  return found;
}

// The sampled plant of the relay's loop: the model (with the hand when one is
// given, as ZWidth samples it) by exact ZOH, its input delay moved into d.
// With friction, an encoder or actuator limits: the continuous realisation
// (period_s 0), which SimulateLoop runs on the stick-slip plant.
model::StateSpace RelayPlant(const model::Plant& plant, const RelayOptions& o) {
  if (o.Nonlinear()) return ContinuousStateSpaceWithHand(plant, o.loop.hand);
  model::StateSpace ss = o.loop.hand.IsNone()
                      ? model::DiscretizeZoh(plant, o.period_s)
                      : model::DiscretizeZoh(ContinuousStateSpaceWithHand(plant, o.loop.hand), o.period_s);
  ss.delay_samples = 0;
  return ss;
}

}  // namespace

RelayResult SimulateRelay(const model::Plant& plant, const RelayOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  plant.Validate();
  const model::StateSpace ss = RelayPlant(plant, o);
  const int d = o.delay_samples + plant.delay_samples;
  WindowCache windows;
  Run base = RunOnce(ss, d, o, 0.0, windows);  // the plain relay
  RelayResult r = std::move(base.r);
  if (!r.oscillating()) {
    if (r.status == RelayStatus::kDiverged) r.K_cr = r.K_cr_peak = 0.0;  // no K > 0 is stable
    return r;
  }
  const double to_hz = 1.0 / (2.0 * std::numbers::pi * o.period_s);
  // The paper's reading: the spectral peak, and |F1|/|X1| there.
  r.K_cr_peak = 1.0 / std::abs(base.L);
  r.f_cr_peak_hz = base.theta * to_hz;
  r.K_cr = r.K_cr_peak;
  r.f_cr_hz = r.f_cr_peak_hz;
  r.unsettled = base.unsettled;
  const size_t steady = r.position.size() - static_cast<size_t>(o.settle_fraction * r.position.size());
  const double theta_min = 2.0 * std::numbers::pi * 20.0 / static_cast<double>(steady);
  r.band_low_hz = theta_min * to_hz;
  if (!o.refine) {
    r.status = RelayStatus::kPeakReading;
    return r;
  }
  SteeredSearch search(ss, d, o, windows);
  std::vector<Point> scan = search.Scan(theta_min, 0.9 * std::numbers::pi);
  // The lowest run already past -180 deg: a crossing lies below the band, where
  // it cannot be measured in this record.
  if (scan.empty() || scan.front().g < 0.0) {
    r.status = RelayStatus::kBelowBand;
  } else {
    search.ProbeDips(scan);
    r.status = search.RefineCrossings(scan, to_hz, r) ? RelayStatus::kRefined : RelayStatus::kPeakReading;
  }
  r.relay_runs = search.runs() + 1;
  return r;
}

}  // namespace zwidth::stability
