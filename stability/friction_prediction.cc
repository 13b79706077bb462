#include "stability/friction_prediction.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "model/error.h"
#include "stability/sampled_plant.h"
#include "stability/zwidth.h"

namespace zwidth::stability {

std::string ToString(FrictionVerdict v) {
  switch (v) {
    case FrictionVerdict::kLinearStable: return "linear_stable";
    case FrictionVerdict::kStableBelow: return "stable_below_amplitude";
    case FrictionVerdict::kUnstable: return "unstable";
    case FrictionVerdict::kNotRun: break;
  }
  return "not_run";
}

bool FrictionPredictionOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = "FrictionPredictionOptions::" + m; return false; };
  if (!(relative_tolerance > 0 && relative_tolerance < 0.1)) return bad("relative_tolerance must be in (0, 0.1)");
  if (!(max_extra_damping_factor > 1 && std::isfinite(max_extra_damping_factor))) {
    return bad("max_extra_damping_factor must be finite and > 1");
  }
  return true;
}

namespace {

constexpr double kMinEncoderSteps = 10.0;
constexpr double kMinStaticMargin = 3.0;
constexpr double kCrossingSeparation = 0.1;

// The loop with b_e added to the hand's damping.
LoopOptions WithExtraDamping(const LoopOptions& loop, double b_e) {
  LoopOptions l = loop;
  l.hand.B += b_e;
  return l;
}

bool StableWith(const model::Plant& plant, double T, int d, const LoopOptions& loop, double b_e, double K,
                double B) {
  const LoopOptions l = WithExtraDamping(loop, b_e);
  const ZWidth z(SampledPlant(plant, T, l.hand), d, l);
  return K > 0.0 ? z.IsStable(K, B) : !z.At(B).unstable_at_zero_k;
}

// The crossing at b_e nearest K: its frequency, and whether another lies within 10 % of K.
void CrossingAt(const model::Plant& plant, double T, int d, const LoopOptions& loop, double b_e, double K,
                double B, FrictionPrediction* p) {
  const LoopOptions l = WithExtraDamping(loop, b_e);
  const ZWidth z(SampledPlant(plant, T, l.hand), d, l);
  double best = INFINITY;
  int near = 0;
  for (const Crossing& c : z.Crossings(B)) {
    const double dist = std::abs(c.K - K);
    if (dist <= kCrossingSeparation * K) ++near;
    if (dist < best) {
      best = dist;
      p->frequency_hz = c.theta / (2.0 * std::numbers::pi * T);
    }
  }
  if (near > 1 && p->invalid_reason.empty()) p->invalid_reason = "several_crossings_near_K";
}

}  // namespace

FrictionPrediction PredictFriction(const model::Plant& plant, double T, int delay, const LoopOptions& loop,
                                   double K, double B, const model::Friction& friction, double q,
                                   const FrictionPredictionOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  friction.Validate();
  if (!(std::isfinite(K) && K >= 0 && std::isfinite(B) && B >= 0)) {
    throw InputError("friction prediction: K and B must be finite and >= 0");
  }
  if (!(std::isfinite(q) && q >= 0)) throw InputError("friction prediction: the encoder step must be finite, >= 0");
  FrictionPrediction p;
  const double fc = friction.MeanCoulomb();
  if (q > 0.0) {
    p.K_rest_max = 2.0 * fc / q;
    p.rest_point_ok = K * q <= 2.0 * fc;
  }
  const ZWidth linear(SampledPlant(plant, T, loop.hand), delay, loop);
  p.K_cr_linear = linear.At(B).K_cr;
  if (StableWith(plant, T, delay, loop, 0.0, K, B)) {
    p.verdict = FrictionVerdict::kLinearStable;
    p.amplitude = INFINITY;
    p.valid = true;
    return p;
  }
  const double scale = plant.b + loop.hand.B + B + 1e-9;
  double lo = 0.0, hi = 1e-3 * scale;
  while (!StableWith(plant, T, delay, loop, hi, K, B)) {
    lo = hi;
    hi *= 2.0;
    if (hi > o.max_extra_damping_factor * scale || fc == 0.0) {
      p.verdict = FrictionVerdict::kUnstable;
      p.invalid_reason = fc == 0.0 ? "no_friction" : "no_extra_damping_stabilises";
      return p;
    }
  }
  while (hi - lo > o.relative_tolerance * hi) {
    const double mid = 0.5 * (lo + hi);
    (StableWith(plant, T, delay, loop, mid, K, B) ? hi : lo) = mid;
  }
  p.extra_damping = hi;
  CrossingAt(plant, T, delay, loop, hi, K, B, &p);
  p.verdict = FrictionVerdict::kStableBelow;
  p.amplitude = 4.0 * fc / (std::numbers::pi * 2.0 * std::numbers::pi * p.frequency_hz * p.extra_damping);
  const double f_static = std::max(friction.StaticPos(), friction.StaticNeg());
  if (p.invalid_reason.empty() && q > 0.0 && p.amplitude < kMinEncoderSteps * q) {
    p.invalid_reason = "amplitude_below_10_encoder_steps";
  }
  if (p.invalid_reason.empty() && K * p.amplitude < kMinStaticMargin * f_static) {
    p.invalid_reason = "wall_force_below_3x_static_level";
  }
  p.valid = p.invalid_reason.empty();
  return p;
}

}  // namespace zwidth::stability
