#include "analysis/table2.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include "io/stability_files.h"
#include "model/c_locale.h"
#include "model/error.h"
#include "model/simulate.h"
#include "model/friction.h"
#include "model/parallel.h"
#include "stability/relay.h"
#include "stability/sampled_plant.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {
namespace {

bool Positive(double x) { return std::isfinite(x) && x > 0.0; }

Table2Prediction Prediction(double K, double f_hz, const io::Table2Point& p) {
  Table2Prediction r;
  r.K = K;
  r.f_hz = Positive(K) ? f_hz : std::numeric_limits<double>::quiet_NaN();
  if (Positive(K)) r.K_rel_error = (K - p.K_cr) / p.K_cr;
  if (Positive(r.f_hz)) r.f_rel_error = (r.f_hz - p.f_cr_hz) / p.f_cr_hz;
  return r;
}

// sqrt(mean ln(K / K_measured)^2) over the scored rows; inf when one has no K.
double LogError(const std::vector<Table2Row>& rows, const std::vector<const Table2Prediction*>& pred) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].scored) continue;
    if (!Positive(pred[i]->K)) return std::numeric_limits<double>::infinity();
    const double e = std::log(pred[i]->K / rows[i].point.K_cr);
    sum += e * e;
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : std::numeric_limits<double>::quiet_NaN();
}

std::string Num(const char* fmt, double x) {
  char s[64];
  std::snprintf(s, sizeof s, fmt, x);
  return s;
}

// "2.50@7.31 -65%" (K at f, % of K from the point); "none" without a K.
std::string Cell(const Table2Prediction& p) {
  if (p.K == 0.0) return "0 (diverged)";
  if (!Positive(p.K)) return std::isinf(p.K) ? "inf" : "none";
  std::string s = Num("%.3g", p.K) + "@" + Num("%.3g", p.f_hz);
  if (std::isfinite(p.K_rel_error)) s += " " + Num("%+.0f%%", 100.0 * p.K_rel_error);
  if (p.unsettled > 1e-3) s += "~";  // not a steady oscillation (RelayResult::unsettled)
  return s;
}

nlohmann::json PredictionJson(const Table2Prediction& p) {
  const auto num = io::NumberOrNull;
  return {{"K", std::isinf(p.K) ? nlohmann::json("inf") : num(p.K)},
          {"f_hz", num(p.f_hz)},
          {"K_rel_error", num(p.K_rel_error)},
          {"f_rel_error", num(p.f_rel_error)},
          {"unsettled", num(p.unsettled)}};
}

}  // namespace

bool Table2Options::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = "Table2Options::" + m; return false; };
  if (coulomb_levels.empty() || coulomb_levels.size() > 64) return bad("coulomb_levels must hold 1 to 64 levels");
  for (double f : coulomb_levels) {
    if (!(std::isfinite(f) && f >= 0.0 && f <= 1e6)) return bad("coulomb_levels: each level must be finite, >= 0 and <= 1e6 N m");
  }
  for (size_t i = 0; i < coulomb_levels.size(); ++i) {  // a level twice was simulated twice, its column twice
    for (size_t k = 0; k < i; ++k) {
      if (coulomb_levels[k] == coulomb_levels[i]) {
        return bad("coulomb_levels: the level " + FormatG(coulomb_levels[i]) + " is given twice; give each once");
      }
    }
  }
  if (!(std::isfinite(encoder_step) && encoder_step >= 0.0)) return bad("encoder_step must be finite and >= 0");
  if (std::string p = model::EncoderStepProblem(encoder_step, "encoder_step"); !p.empty()) return bad(p);
  if (!(std::isfinite(relay_amplitude) && relay_amplitude > 0.0)) return bad("relay_amplitude must be finite and > 0");
  if (!(seconds >= 1.0 && seconds <= 600.0)) return bad("seconds must be in [1, 600]");
  return true;
}

Table2Comparison CompareTable2(const model::Plant& plant, double period_s, const std::vector<io::Table2Point>& points,
                               const Table2Options& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  plant.Validate();
  if (!(std::abs(period_s - 1e-3) <= 1e-12)) {
    throw InputError("Table II was measured at T = 1 ms (its delays are samples of 1 ms), not at the period " +
                     Num("%.6g", period_s) + " s: compare the model at 0.001 s");
  }
  Table2Comparison c;
  c.coulomb_levels = o.coulomb_levels;
  c.encoder_step = o.encoder_step;
  c.relay_amplitude = o.relay_amplitude;
  c.seconds = o.seconds;
  const size_t L = o.coulomb_levels.size();
  // Linear: one ZWidth per delay, on one sampled plant.
  const stability::SampledPlant sampled(plant, period_s);
  std::map<int, stability::ZWidth> zwidths;
  // Relay: one run per distinct (delay, B) and level (Table II repeats a B).
  std::vector<std::pair<int, double>> keys;
  std::vector<size_t> key_of;
  for (const io::Table2Point& p : points) {
    const auto it = zwidths.try_emplace(p.delay_samples, sampled, p.delay_samples).first;
    const stability::CriticalPoint cp = it->second.At(p.B);
    Table2Row row;
    row.point = p;
    row.linear = Prediction(cp.K_cr, cp.f_cr_hz, p);
    row.scored = Positive(cp.K_cr);
    c.num_scored += row.scored ? 1 : 0;
    c.rows.push_back(row);
    size_t k = 0;
    while (k < keys.size() && keys[k] != std::make_pair(p.delay_samples, p.B)) ++k;
    if (k == keys.size()) keys.emplace_back(p.delay_samples, p.B);
    key_of.push_back(k);
  }
  struct Reading {
    double K, f_hz, unsettled;
  };
  std::vector<Reading> readings(keys.size() * L);  // per key and level
  ParallelFor(readings.size(), [&](size_t i) {
    stability::RelayOptions ro;
    ro.period_s = period_s;
    ro.delay_samples = keys[i / L].first;
    ro.damping = keys[i / L].second;
    ro.amplitude = o.relay_amplitude;
    ro.seconds = o.seconds;
    ro.friction = model::Friction::Symmetric(o.coulomb_levels[i % L]);
    ro.encoder_step = o.encoder_step;
    ro.refine = false;  // the paper's reading
    const stability::RelayResult r = stability::SimulateRelay(plant, ro);
    readings[i] = {r.K_cr_peak, r.f_cr_peak_hz, r.unsettled};
  });
  c.relay_runs = static_cast<int>(readings.size());
  for (size_t j = 0; j < c.rows.size(); ++j) {
    for (size_t l = 0; l < L; ++l) {
      const Reading& r = readings[key_of[j] * L + l];
      c.rows[j].relay.push_back(Prediction(r.K, r.f_hz, c.rows[j].point));
      c.rows[j].relay.back().unsettled = r.unsettled;
    }
  }
  std::vector<const Table2Prediction*> pred(c.rows.size());
  for (size_t j = 0; j < c.rows.size(); ++j) pred[j] = &c.rows[j].linear;
  c.linear_error = LogError(c.rows, pred);
  for (size_t l = 0; l < L; ++l) {
    for (size_t j = 0; j < c.rows.size(); ++j) pred[j] = &c.rows[j].relay[l];
    c.relay_error.push_back(LogError(c.rows, pred));
    if (c.relay_error[l] < c.relay_error[c.best_level]) c.best_level = l;
  }
  return c;
}

nlohmann::json Table2Json(const Table2Comparison& c) {
  const auto num = io::NumberOrNull;
  nlohmann::json j;
  j["coulomb_levels"] = c.coulomb_levels;
  j["encoder_step"] = c.encoder_step;
  j["relay_amplitude"] = c.relay_amplitude;
  j["seconds"] = c.seconds;
  j["error_meaning"] = "sqrt(mean of ln(K_predicted / K_measured)^2) over the scored points (those where the linear "
                       "model has a stable K); null: a scored point without a prediction";
  j["num_scored"] = c.num_scored;
  j["linear_error"] = num(c.linear_error);
  j["relay_error"] = nlohmann::json::array();
  for (double e : c.relay_error) j["relay_error"].push_back(num(e));
  j["best_coulomb"] = c.coulomb_levels.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.best_coulomb());
  j["relay_runs"] = c.relay_runs;
  j["points"] = nlohmann::json::array();
  for (const Table2Row& r : c.rows) {
    nlohmann::json p = {{"delay_samples", r.point.delay_samples}, {"B", r.point.B}, {"K_cr", r.point.K_cr},
                        {"f_cr_hz", r.point.f_cr_hz}, {"scored", r.scored}, {"linear", PredictionJson(r.linear)}};
    p["relay"] = nlohmann::json::array();
    for (size_t l = 0; l < r.relay.size(); ++l) {
      nlohmann::json e = PredictionJson(r.relay[l]);
      e["coulomb"] = c.coulomb_levels[l];
      p["relay"].push_back(e);
    }
    j["points"].push_back(p);
  }
  return j;
}

std::string Table2Text(const Table2Comparison& c) {
  std::string s = "Table II (the paper's relay on the real PHANToM) beside the model: K_cr@f_cr [N m/rad@Hz], % of K "
                  "from the point\nrelay: simulated with Coulomb F_c at the motor, encoder step " +
                  Num("%.6g", c.encoder_step) + " rad, amplitude " + Num("%g", c.relay_amplitude) + " N m, " +
                  Num("%g", c.seconds) + " s, read at the spectral peak (as the paper read it); ~: the oscillation was still "
                  "settling (the two halves' |L| more than 0.1 % apart)\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-2s %-6s %-14s %-18s", "d", "B", "measured", "linear exact");
  s += line;
  for (double f : c.coulomb_levels) {
    std::snprintf(line, sizeof line, " %-18s", ("F_c " + Num("%g", f)).c_str());
    s += line;
  }
  s += "\n";
  for (const Table2Row& r : c.rows) {
    std::snprintf(line, sizeof line, "%-2d %-6g %-14s %-18s", r.point.delay_samples, r.point.B,
                  (Num("%.4g", r.point.K_cr) + "@" + Num("%.4g", r.point.f_cr_hz)).c_str(), Cell(r.linear).c_str());
    s += line;
    for (const Table2Prediction& p : r.relay) {
      std::snprintf(line, sizeof line, " %-18s", Cell(p).c_str());
      s += line;
    }
    s += r.scored ? "\n" : "  (past the linear B_max: not scored)\n";
  }
  s += "error, sqrt(mean ln(K_predicted / K_measured)^2) over " + std::to_string(c.num_scored) + " points: linear " +
       Num("%.3g", c.linear_error);
  for (size_t l = 0; l < c.relay_error.size(); ++l) {
    s += ", F_c " + Num("%g", c.coulomb_levels[l]) + ": " + Num("%.3g", c.relay_error[l]);
  }
  s += "\nbest Coulomb level of the grid: F_c = " + Num("%g", c.best_coulomb()) + " N m (error " +
       Num("%.3g", c.relay_error[c.best_level]) + "; it scales with F_c / relay amplitude)\n";
  return s;
}

}  // namespace zwidth::analysis
