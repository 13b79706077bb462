#include "io/stability_files.h"

#include "io/io_internal.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <unordered_set>

#include "io/atomic_file.h"
#include "model/c_locale.h"
#include "stability/loop_options.h"
#include "io/model_json.h"
#include "model/error.h"

namespace zwidth::io {

nlohmann::json NumberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

void WriteBoundaryCsv(const std::string& path, const std::vector<BoundaryRow>& rows) {
  WriteAtomically(path, [&](const std::string& tmp) {
    internal::CsvFile line(tmp);
    const bool friction = std::any_of(rows.begin(), rows.end(), [](const BoundaryRow& r) { return r.A_star_valid >= 0; });
    line.Text("delay_samples,B,interval,num_intervals,K_lo,K_hi,f_lo_hz,f_hi_hz,interval_verified,"
              "K_cr,K_cr_std,f_cr_hz,K_margin,f_margin_hz,unstable_at_zero_k,margin_agrees,verified,K_passive");
    line.Text(friction ? ",friction_K,A_star,A_star_f_hz,A_star_valid\n" : "\n");
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const BoundaryRow& r : rows) {
      const auto& p = r.point;
      const int n = static_cast<int>(r.intervals.size());
      for (int i = 0; i < std::max(n, 1); ++i) {
        const stability::KInterval iv = n ? r.intervals[i] : stability::KInterval{nan, nan, nan, nan, false};
        line.Int(r.delay_samples).G(p.B, 12).Int(n ? i : -1).Int(n);
        line.G(iv.K_lo, 15).G(iv.K_hi, 15).G(iv.f_lo_hz, 15).G(iv.f_hi_hz, 15).Int(iv.verified ? 1 : 0);
        line.G(p.K_cr, 15).G(r.K_cr_std, 6).G(p.f_cr_hz, 15).G(p.K_margin, 15).G(p.f_margin_hz, 15);
        line.Int(p.unstable_at_zero_k ? 1 : 0).Int(p.AgreesWithMargin() ? 1 : 0).Int(p.verified ? 1 : 0);
        line.G(r.K_passive, 15);
        if (friction) line.G(r.friction_K, 15).G(r.A_star, 15).G(r.A_star_f_hz, 15).Int(r.A_star_valid);
        line.End();
      }
    }
    line.Close(path);
  });
}

nlohmann::json IntervalsToJson(const std::vector<stability::KInterval>& intervals) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& iv : intervals) {
    a.push_back({{"K_lo", iv.K_lo}, {"K_hi", NumberOrNull(iv.K_hi)}, {"f_lo_hz", NumberOrNull(iv.f_lo_hz)},
                 {"f_hi_hz", NumberOrNull(iv.f_hi_hz)}, {"verified", iv.verified}});
  }
  return a;
}

nlohmann::json SummaryToJson(const stability::DelaySummary& s, const stability::SummaryStd* std) {
  nlohmann::json bands = nlohmann::json::array();
  for (const auto& b : s.reopened_bands) {
    bands.push_back({{"B_lo", b.B_lo}, {"B_hi", b.B_hi}, {"K_max", NumberOrNull(b.K_max)}});
  }
  nlohmann::json jumps = nlohmann::json::array();
  for (const auto& f : s.frequency_jumps) {
    jumps.push_back({{"B", f.B}, {"K_before", NumberOrNull(f.K_before)}, {"K_after", NumberOrNull(f.K_after)},
                     {"f_before_hz", NumberOrNull(f.f_before_hz)}, {"f_after_hz", NumberOrNull(f.f_after_hz)}});
  }
  nlohmann::json j = {{"delay_samples", s.delay_samples},
          {"K_cr_at_zero_B", NumberOrNull(s.K_cr_at_zero_B)},
          {"f_at_zero_B_hz", NumberOrNull(s.f_at_zero_B_hz)},
          {"B_t", NumberOrNull(s.B_t)},
          {"K_cr_max", NumberOrNull(s.K_cr_max)},
          {"B_at_K_cr_max", NumberOrNull(s.B_at_K_cr_max)},
          {"f_before_hz", NumberOrNull(s.f_before_hz)},
          {"f_after_hz", NumberOrNull(s.f_after_hz)},
          {"B_max", NumberOrNull(s.B_max)},
          {"B_max_from_zero", NumberOrNull(s.B_max_from_zero)},
          {"reopened_bands", bands},
          {"frequency_jumps", jumps},
          {"stability_test", {{"method", s.polynomial_test ? "schur-cohn" : "eigenvalues"},
                              {"polynomial_error", NumberOrNull(s.polynomial_error)},
                              {"pole_shift", NumberOrNull(s.pole_shift)},
                              {"conditioning", {{"relative_separation", NumberOrNull(s.conditioning.relative_separation)},
                                                {"eigenvalue_condition", NumberOrNull(s.conditioning.eigenvalue_condition)},
                                                {"eigenvalue_shift", NumberOrNull(s.conditioning.eigenvalue_shift)}}},
                              {"warning", s.conditioning_warning.empty() ? nlohmann::json(nullptr)
                                                                         : nlohmann::json(s.conditioning_warning)}}}};
  if (std) {
    j["std"] = {{"K_cr_at_zero_B", NumberOrNull(std->K_cr_at_zero_B)}, {"B_t", NumberOrNull(std->B_t)},
                {"K_cr_max", NumberOrNull(std->K_cr_max)}, {"B_max", NumberOrNull(std->B_max)}};
  }
  return j;
}

namespace {

// '{' outside strings: at least the number of objects a scene holds, plus one.
size_t CountJsonObjects(const std::string& text) {
  size_t n = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{') {
      ++n;
    }
  }
  return n;
}

}  // namespace

std::string LoopDelaysProblem(const std::vector<int>& delays, const std::string& name) {
  if (delays.empty()) return name + " is empty: give at least one delay [samples]";
  if (delays.size() > kMaxLoopDelays) {
    return name + ": " + std::to_string(delays.size()) + " delays, more than the " + std::to_string(kMaxLoopDelays) +
           " one command takes: run it again for the others";
  }
  for (size_t i = 0; i < delays.size(); ++i) {
    const int d = delays[i];
    if (d < 0 || d > kMaxLoopDelaySamples) {
      return name + " = " + std::to_string(d) + ": a loop delay must lie in [0, " +
             std::to_string(kMaxLoopDelaySamples) + "] samples (a delay counts samples of the period, not ms or us)";
    }
    // A delay twice would be computed twice and give its rows and summary twice
    // (a boundary CSV with repeated rows, a comparison printed twice).
    for (size_t k = 0; k < i; ++k) {
      if (delays[k] == d) {
        return name + ": the delay " + std::to_string(d) + " is given twice (items " + std::to_string(k + 1) +
               " and " + std::to_string(i + 1) + "): give each delay once";
      }
    }
  }
  return "";
}

std::vector<SceneObject> ReadScene(const std::string& path) {
  return ParseScene(ReadSmallFile(path, "scene file", kMaxSceneBytes), path);  // a regular file, bounded size
}

std::vector<SceneObject> ParseScene(const std::string& text, const std::string& path) {
  CheckNotJsonOfAnotherKind(text, path, "scene", "check");
  CheckJsonDepth(text, path);
  if (CountJsonObjects(text) > kMaxSceneObjects + 1) {
    throw InputError(path + ": more than " + std::to_string(kMaxSceneObjects) +
                     " objects (the most `check` takes in one scene): split the scene into several files");
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // parse_error, out_of_range (1e999)
    throw InputError(path + ": not valid JSON (truncated or malformed): " + e.what());
  }
  CheckDuplicateKeys(text, path);
  if (!j.is_object() || !j.contains("objects") || !j["objects"].is_array()) {
    throw InputError(path + ": expected {\"objects\": [{\"name\": ..., \"K\": ..., \"B\": ...}, ...]}");
  }
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (it.key() != "objects") throw InputError(path + ": unknown key '" + it.key() + "'");
  }
  std::vector<SceneObject> out;
  std::unordered_set<std::string> names;
  const auto& arr = j["objects"];
  for (size_t i = 0; i < arr.size(); ++i) {
    const auto& o = arr[i];
    const std::string where = path + ": objects[" + std::to_string(i) + "]";
    if (!o.is_object()) throw InputError(where + " must be an object");
    for (auto it = o.begin(); it != o.end(); ++it) {
      if (it.key() != "name" && it.key() != "K" && it.key() != "B") {
        throw InputError(where + ": unknown key '" + it.key() + "' (allowed: name, K, B)");
      }
    }
    SceneObject so;
    // A name, when given, is what a report and a CI gate read the verdict by:
    // a non-empty string, once per scene. Without one: "object<i>".
    if (o.contains("name") && (!o["name"].is_string() || o["name"].get<std::string>().empty())) {
      throw InputError(where + ": 'name' = " + o["name"].dump().substr(0, 40) +
                       " must be a non-empty string (or leave it out: the object is then called object" +
                       std::to_string(i) + ")");
    }
    so.name = o.contains("name") ? o["name"].get<std::string>() : "object" + std::to_string(i);
    if (!names.insert(so.name).second) {
      throw InputError(where + ": the name '" + so.name.substr(0, 40) +
                       "' is already used by an earlier object: give each object its own name");
    }
    for (const char* key : {"K", "B"}) {
      if (!o.contains(key) || !o[key].is_number()) {
        throw InputError(where + ": '" + key + "' must be a number");
      }
      const double v = o[key].get<double>();
      // The bound of --stiffness and --damping (wall) and of a hand's K and B.
      if (!std::isfinite(v) || v < 0.0 || v > stability::kMaxLoopValue) {
        throw InputError(where + ": '" + key + "' = " + FormatG(v) + " must be finite and in [0, 1e12] (" +
                         (key[0] == 'K' ? "N m/rad; N/m" : "N m s/rad; N s/m") + " on a linear axis)");
      }
      (key[0] == 'K' ? so.K : so.B) = v;
    }
    out.push_back(so);
  }
  if (out.empty()) throw InputError(path + ": the scene has no objects");
  return out;
}

ObjectVerdict CheckObject(const stability::ZWidth& z, const SceneObject& o) {
  return Classify(o, z.At(o.B), z.StableIntervals(o.B));
}

ObjectVerdict Classify(const SceneObject& o, const stability::CriticalPoint& critical,
                       std::vector<stability::KInterval> intervals) {
  ObjectVerdict v;
  v.critical = critical;
  v.intervals = std::move(intervals);
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < v.intervals.size(); ++i) {
    const stability::KInterval& iv = v.intervals[i];
    const bool in = (o.K > iv.K_lo || (o.K == 0.0 && iv.K_lo == 0.0)) && o.K < iv.K_hi;
    if (in) v.interval = static_cast<int>(i);
    const double dist = o.K <= iv.K_lo ? iv.K_lo - o.K : o.K - iv.K_hi;
    if (dist < best) { best = dist; v.nearest_interval = static_cast<int>(i); }
  }
  v.stable = v.interval >= 0;
  return v;
}

nlohmann::json ObjectVerdict::ToJson(const SceneObject& o) const {
  const double ratio = critical.K_cr > 0.0 ? o.K / critical.K_cr : std::numeric_limits<double>::infinity();
  return {{"name", o.name}, {"K", o.K}, {"B", o.B}, {"stable", stable},
          {"K_cr", NumberOrNull(critical.K_cr)},
          {"f_cr_hz", NumberOrNull(critical.f_cr_hz)},
          {"K_over_K_cr", NumberOrNull(ratio)},
          {"unstable_at_any_K", intervals.empty()},
          {"intervals", IntervalsToJson(intervals)},
          {"interval", stable ? nlohmann::json(interval) : nlohmann::json(nullptr)},
          {"nearest_interval", nearest_interval >= 0 ? nlohmann::json(nearest_interval) : nlohmann::json(nullptr)}};
}

// The largest B >= 0 with a passive K >= 0 (bisection on "the passive set is
// empty", which grows with B for the positive part of the condition).
double PassiveBMax(const stability::Passivity& pa, double b) {
  if (pa.At(0.0).passive_set_empty) return 0.0;
  double lo = 0.0, hi = b;
  for (int i = 0; i < 60 && !pa.At(hi).passive_set_empty; ++i) { lo = hi; hi *= 2.0; }
  if (!pa.At(hi).passive_set_empty) return std::numeric_limits<double>::infinity();
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (pa.At(mid).passive_set_empty ? hi : lo) = mid;
  }
  return lo;
}

nlohmann::json MonteCarloJson(const stability::MonteCarloResult& mc, std::uint64_t seed) {
  return {{"samples", mc.samples}, {"seed", seed},
          {"std", SummaryToJson(stability::DelaySummary{}, &mc.std)["std"]},
          {"mean", SummaryToJson(stability::DelaySummary{}, &mc.mean)["std"]}};
}

nlohmann::json PassivitySummaryJson(const stability::Passivity& pa, double b) {
  return {{"K_P_at_zero_B", NumberOrNull(pa.At(0.0).K_hi)}, {"B_P_max", NumberOrNull(PassiveBMax(pa, b))},
          {"physical_damping_b", b},
          {"meaning", "Colgate and Schenkel (1997): K < K_P(B) keeps the sampled wall passive; B_P_max: the largest "
                      "B with a passive K"}};
}

std::string DelayText(int loop_samples, int model_samples) {
  char s[96];
  std::snprintf(s, sizeof s, "loop %d + model %d = %d samples", loop_samples, model_samples,
                loop_samples + model_samples);
  return s;
}

void AddDelays(nlohmann::json* record, int loop_samples, int model_samples) {
  (*record)["delay_samples"] = loop_samples;
  (*record)["model_delay_samples"] = model_samples;
  (*record)["total_delay_samples"] = loop_samples + model_samples;
}

}  // namespace zwidth::io
