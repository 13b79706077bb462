#include "analysis/friction_amplitude.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "model/c_locale.h"
#include "model/error.h"
#include "model/simulate.h"
#include "model/parallel.h"

namespace zwidth::analysis {

double EncoderStepOf(const io::ModelFile& model, std::optional<double> given, const std::string& name) {
  if (!given) return model.encoder_step.value_or(0.0);
  if (!(std::isfinite(*given) && *given >= 0.0)) {
    char b[64];
    std::snprintf(b, sizeof b, "%g", *given);
    throw InputError(name + " " + b + ": must be finite and >= 0 (rad or m per count; 0: an exact encoder)");
  }
  if (std::string p = model::EncoderStepProblem(*given, name); !p.empty()) throw InputError(p);
  return *given;
}

bool FrictionAmplitudeOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = "FrictionAmplitudeOptions::" + m; return false; };
  if (!(k_factor > 1.0 && k_factor <= 100.0)) {
    return bad("k_factor = " + FormatG(k_factor) + " must be in (1, 100] (a multiple of K_cr(B))");
  }
  if (!(std::isfinite(encoder_step) && encoder_step >= 0.0)) return bad("encoder_step must be finite and >= 0");
  if (std::string p = model::EncoderStepProblem(encoder_step, "encoder_step"); !p.empty()) return bad(p);
  if (rows_per_delay < 1) return bad("rows_per_delay must be >= 1");
  std::string w;
  if (!prediction.IsValid(&w)) return bad("prediction: " + w);
  return true;
}

std::vector<FrictionAmplitudeRow> FrictionAmplitudes(const model::Plant& plant, double period_s,
                                                     const stability::LoopOptions& loop,
                                                     const std::vector<io::BoundaryRow>& rows,
                                                     const model::Friction& friction,
                                                     const FrictionAmplitudeOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  friction.Validate();
  std::vector<FrictionAmplitudeRow> out(rows.size());
  // The rows computed: per delay (a run of equal delay_samples), rows_per_delay evenly spaced ones.
  std::vector<char> chosen(rows.size(), 0);
  for (size_t first = 0; first < rows.size();) {
    size_t end = first;
    while (end < rows.size() && rows[end].delay_samples == rows[first].delay_samples) ++end;
    const size_t n = end - first, m = std::min(n, static_cast<size_t>(options.rows_per_delay));
    for (size_t k = 0; k < m; ++k) chosen[first + (m > 1 ? k * (n - 1) / (m - 1) : 0)] = 1;
    first = end;
  }
  ParallelFor(rows.size(), [&](size_t i) {
    const io::BoundaryRow& r = rows[i];
    FrictionAmplitudeRow& a = out[i];
    a.delay_samples = r.delay_samples;
    a.B = r.point.B;
    if (!chosen[i] || !(std::isfinite(r.point.K_cr) && r.point.K_cr > 0.0) || r.point.unstable_at_zero_k) return;
    a.K = options.k_factor * r.point.K_cr;
    a.prediction = stability::PredictFriction(plant, period_s, r.delay_samples, loop, a.K, a.B, friction,
                                              options.encoder_step, options.prediction);
  });
  return out;
}

void SetFrictionColumns(const std::vector<FrictionAmplitudeRow>& amplitudes, std::vector<io::BoundaryRow>* rows) {
  if (amplitudes.size() != rows->size()) throw ComputationError("SetFrictionColumns: rows and amplitudes differ in size");
  for (size_t i = 0; i < rows->size(); ++i) {
    io::BoundaryRow& r = (*rows)[i];
    const FrictionAmplitudeRow& a = amplitudes[i];
    r.friction_K = a.K;
    r.A_star = a.prediction.amplitude;
    r.A_star_f_hz = a.prediction.frequency_hz;
    r.A_star_valid = a.prediction.verdict == stability::FrictionVerdict::kNotRun ? -1 : a.prediction.valid ? 1 : 0;
  }
}

nlohmann::json FrictionPredictionJson(const stability::FrictionPrediction& p) {
  return {{"verdict", stability::ToString(p.verdict)},
          {"amplitude", io::NumberOrNull(p.amplitude)},
          {"frequency_hz", io::NumberOrNull(p.frequency_hz)},
          {"extra_damping", io::NumberOrNull(p.extra_damping)},
          {"K_cr_linear", io::NumberOrNull(p.K_cr_linear)},
          {"valid", p.valid},
          {"invalid_reason", p.invalid_reason},
          {"rest_point_ok", p.rest_point_ok},
          {"K_rest_max", io::NumberOrNull(p.K_rest_max)}};
}

nlohmann::json FrictionAmplitudeRowJson(const FrictionAmplitudeRow& r) {
  nlohmann::json j = FrictionPredictionJson(r.prediction);
  j["B"] = r.B;
  j["K"] = io::NumberOrNull(r.K);
  return j;
}

namespace {

const FrictionAmplitudeRow* ZeroBRow(const std::vector<FrictionAmplitudeRow>& rows, int d) {
  for (const FrictionAmplitudeRow& r : rows) {
    if (r.delay_samples == d && r.B == 0.0) return &r;
  }
  return nullptr;
}

}  // namespace

nlohmann::json FrictionSummaryJson(const std::vector<FrictionAmplitudeRow>& rows, int d,
                                   const model::Friction& friction, const FrictionAmplitudeOptions& options) {
  nlohmann::json j = {{"coulomb", friction.MeanCoulomb()},
                      {"k_factor", options.k_factor},
                      {"encoder_step", options.encoder_step},
                      {"K_rest_max", options.encoder_step > 0.0
                                         ? nlohmann::json(2.0 * friction.MeanCoulomb() / options.encoder_step)
                                         : nlohmann::json(nullptr)},
                      {"meaning", "a wall at K = k_factor x K_cr(B), outside the linear Z-width, is stable for "
                                  "oscillations below amplitude A* (describing function of Coulomb friction, "
                                  "docs/friction.md); valid false: outside the prediction's validity"}};
  const FrictionAmplitudeRow* z = ZeroBRow(rows, d);
  j["at_zero_B"] = z ? FrictionAmplitudeRowJson(*z) : nlohmann::json(nullptr);
  return j;
}

std::string FrictionSummaryLine(const std::vector<FrictionAmplitudeRow>& rows, int d,
                                const FrictionAmplitudeOptions& options, const model::UnitLabels& units) {
  const FrictionAmplitudeRow* z = ZeroBRow(rows, d);
  char buf[320];
  if (!z || !std::isfinite(z->K)) {
    std::snprintf(buf, sizeof buf, "d = %d friction: no K_cr(0) > 0, no amplitude prediction", d);
    return buf;
  }
  const stability::FrictionPrediction& p = z->prediction;
  if (p.verdict != stability::FrictionVerdict::kStableBelow) {
    std::snprintf(buf, sizeof buf, "d = %d friction: a wall at %g K_cr(0) = %.6g %s: %s", d, options.k_factor, z->K,
                  units.K, stability::ToString(p.verdict).c_str());
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "d = %d friction: a wall at %g K_cr(0) = %.6g %s is stable below A* = %.4g %s (%.4g Hz)%s%s", d,
                options.k_factor, z->K, units.K, p.amplitude, units.position, p.frequency_hz,
                p.valid ? "" : ", outside validity: ", p.invalid_reason.c_str());
  return buf;
}

}  // namespace zwidth::analysis
