#include "stability/wall_simulation.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>

#include "model/error.h"
#include "model/simulate.h"
#include "model/nonlinear_simulate.h"
#include "model/state_space.h"
#include "stability/hand.h"
#include "stability/velocity_filter_internal.h"

namespace zwidth::stability {

bool WallOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = "WallOptions::" + m; return false; };
  if (!(std::isfinite(period_s) && period_s > 0)) return bad("period_s must be finite and > 0");
  if (delay_samples < 0) return bad("delay_samples must be >= 0");
  // Past 1e12 (the model file's range for m and b) K x and B v overflow the
  // simulation's arithmetic long before any device could render them.
  if (!(std::isfinite(stiffness) && stiffness >= 0 && stiffness <= 1e12)) return bad("stiffness must lie in [0, 1e12]");
  if (!(std::isfinite(damping) && damping >= 0 && damping <= 1e12)) return bad("damping must lie in [0, 1e12]");
  if (!(std::isfinite(seconds) && seconds > 0)) return bad("seconds must be finite and > 0");
  if (seconds / period_s < 64) return bad("seconds must give at least 64 samples");
  if (seconds / period_s > 5e7) return bad("seconds / period_s is over 5e7 samples: simulate less");
  if (!(std::isfinite(initial_position) && initial_position != 0.0 && std::abs(initial_position) <= 1e6)) {
    return bad("initial_position must be != 0 (the wall is at 0) and within +-1e6");
  }
  if (!(std::isfinite(encoder_step) && encoder_step >= 0)) return bad("encoder_step must be finite and >= 0");
  if (std::string p = model::EncoderStepProblem(encoder_step, "encoder_step"); !p.empty()) return bad(p);
  std::string w;
  if (!friction.IsValid(&w)) return bad("friction." + w);
  if (!actuator.IsValid(&w)) return bad("actuator." + w);
  if (!loop.IsValid(&w)) return bad("loop." + w);
  return true;
}

std::string ToString(WallOutcome o) {
  switch (o) {
    case WallOutcome::kDecays: return "decays";
    case WallOutcome::kLimitCycle: return "limit_cycle";
    case WallOutcome::kGrows: return "grows";
    case WallOutcome::kUnsettled: return "unsettled";
    case WallOutcome::kNotRun: break;
  }
  return "not_run";
}

namespace {

constexpr double kGrowthBound = 1e4;    // |y| past this x the start: grows, stop
constexpr double kDeadFraction = 1e-3;  // last amplitude under this x the first: decays
constexpr double kSteady = 0.03;        // |ratio - 1| under this between eighths: steady

double HalfPeakToPeak(const std::vector<double>& y, size_t a, size_t b) {
  const auto [lo, hi] = std::minmax_element(y.begin() + a, y.begin() + b);
  return 0.5 * (*hi - *lo);
}

// Mean crossings of y[a, b) -> frequency [Hz].
double CrossingFrequency(const std::vector<double>& y, size_t a, size_t b, double T) {
  double mean = 0.0;
  for (size_t k = a; k < b; ++k) mean += y[k];
  mean /= static_cast<double>(b - a);
  long first = -1, last = -1, count = 0;
  for (size_t k = a + 1; k < b; ++k) {
    if ((y[k - 1] - mean < 0.0) != (y[k] - mean < 0.0)) {
      if (first < 0) first = static_cast<long>(k);
      last = static_cast<long>(k);
      ++count;
    }
  }
  if (count < 3) return std::numeric_limits<double>::quiet_NaN();
  return 0.5 * static_cast<double>(count - 1) / (static_cast<double>(last - first) * T);
}

void Classify(double x0, double T, WallResult* r) {
  const std::vector<double>& y = r->position;
  const size_t n = y.size(), w = n / 8;
  r->initial_amplitude = HalfPeakToPeak(y, 0, w);
  r->amplitude = HalfPeakToPeak(y, n - w, n);
  const double prev = HalfPeakToPeak(y, n - 2 * w, n - w), prev2 = HalfPeakToPeak(y, n - 3 * w, n - 2 * w);
  r->last_ratio = prev > 0.0 ? r->amplitude / prev : (r->amplitude > 0.0 ? INFINITY : 1.0);
  double mean = 0.0;
  for (size_t k = n - w; k < n; ++k) mean += y[k];
  r->rest_position = mean / static_cast<double>(w);
  r->frequency_hz = CrossingFrequency(y, n - 2 * w, n, T);
  const double ratio2 = prev2 > 0.0 ? prev / prev2 : 1.0;
  if (!std::isfinite(r->amplitude) || n < r->samples || std::abs(y.back()) > kGrowthBound * std::abs(x0)) {
    r->outcome = WallOutcome::kGrows;
  } else if (r->amplitude <= kDeadFraction * r->initial_amplitude || r->amplitude == 0.0) {
    r->outcome = WallOutcome::kDecays;
  } else if (std::abs(r->last_ratio - 1.0) < kSteady && std::abs(ratio2 - 1.0) < kSteady) {
    r->outcome = WallOutcome::kLimitCycle;
  } else if (r->last_ratio > 1.0 + kSteady && ratio2 > 1.0 + kSteady && r->amplitude > r->initial_amplitude) {
    r->outcome = WallOutcome::kGrows;
  } else if (r->last_ratio < 1.0 - kSteady && ratio2 < 1.0 - kSteady) {
    r->outcome = WallOutcome::kDecays;
  } else {
    r->outcome = WallOutcome::kUnsettled;
  }
}

}  // namespace

WallResult SimulateWall(const model::Plant& plant, const WallOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  plant.Validate();
  const model::StateSpace c = ContinuousStateSpaceWithHand(plant, o.loop.hand);
  model::StickSlipPlant device(c, o.friction, o.period_s);
  // At rest at initial_position: the rigid body's position state (the cascade's
  // last pair, model/state_space.h) is m theta; the sections are relaxed.
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(c.A.rows());
  x0(c.A.rows() - 2) = o.initial_position / c.C(c.A.rows() - 2);
  device.Reset(x0);
  const size_t n = static_cast<size_t>(std::llround(o.seconds / o.period_s));
  const size_t d = static_cast<size_t>(o.delay_samples + plant.delay_samples);
  WallResult r;
  r.samples = n;
  r.position.reserve(n);
  r.measured.reserve(n);
  r.force.reserve(n);
  internal::VelocityFilter velocity(o.loop);
  std::deque<double> pending(d, 0.0);
  const double bound = kGrowthBound * std::abs(o.initial_position);
  double y_prev = std::nan("");
  for (size_t k = 0; k < n; ++k) {
    const double y = device.position();
    const double ym = o.encoder_step > 0.0 ? o.encoder_step * std::round(y / o.encoder_step) : y;
    if (std::isnan(y_prev)) y_prev = ym;  // at rest before the start
    const double cmd = -(o.stiffness * ym + o.damping * velocity.Step((ym - y_prev) / o.period_s));
    y_prev = ym;
    pending.push_back(cmd);
    const double u = o.actuator.Apply(pending.front());
    pending.pop_front();
    r.position.push_back(y);
    r.measured.push_back(ym);
    r.force.push_back(u);
    if (!(std::abs(y) <= bound)) break;
    device.Step(u);
  }
  if (r.position.size() < 16) {  // grew past the bound at once
    r.outcome = WallOutcome::kGrows;
    return r;
  }
  Classify(o.initial_position, o.period_s, &r);
  return r;
}

}  // namespace zwidth::stability
