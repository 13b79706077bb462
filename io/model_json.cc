#include "io/model_json.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <algorithm>
#include <cctype>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "io/atomic_file.h"
#include "io/provenance.h"
#include "model/error.h"
#include "model/units.h"
#include "stability/uncertainty.h"

namespace zwidth::io {
namespace {

using nlohmann::json;

[[noreturn]] void Fail(const std::string& source, const std::string& what) {
  throw InputError(source + ": " + what);
}

void CheckKeys(const json& obj, const std::set<std::string>& allowed,
               const std::string& source, const std::string& where) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (!allowed.count(it.key())) {
      std::string list;
      for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
      Fail(source, "unknown key '" + where + it.key() + "' (allowed: " + list + ")");
    }
  }
}

// A required number; `allow_null` maps null to +inf (standard errors).
double Number(const json& obj, const std::string& key, const std::string& source,
              const std::string& where, bool allow_null = false) {
  auto it = obj.find(key);
  if (it == obj.end()) Fail(source, "missing key '" + where + key + "'");
  if (allow_null && it->is_null()) return std::numeric_limits<double>::infinity();
  if (!it->is_number()) {
    Fail(source, "key '" + where + key + "' must be a number, got " + it->dump());
  }
  const double v = it->get<double>();
  if (!std::isfinite(v)) Fail(source, "key '" + where + key + "' is not finite");
  return v;
}

// Parameters of a model (not its standard errors) must lie in
// [kPlausibleMin, kPlausibleMax] (SI units, rad/s): values outside (m = 1e-300)
// make the Z-width overflow to inf, which no device has.
void CheckPlausible(double v, const std::string& source, const std::string& name) {
  if (v == 0.0 && name != "m" && name.size() >= 1) {  // an undamped body or mode: not a unit slip
    const char last = name.back();
    if (last == 'b' || last == 'c' || last == 'd') {
      Fail(source, "key '" + name + "' = 0: " + name.substr(name.rfind('.') + 1) + " must be > 0; use e.g. 1e-12 " +
                       (last == 'b' ? "for an undamped body" : "for an undamped mode"));
    }
  }
  if (!(v >= kPlausibleMin && v <= kPlausibleMax)) {
    char b[64];
    std::snprintf(b, sizeof b, "%g", v);
    const char last = name.back();
    const char* unit = last == 'm' ? "kg m^2 (kg on a linear axis)"
                       : last == 'b' ? "N m s/rad (N s/m on a linear axis)"
                                     : "rad/s";
    Fail(source, "key '" + name + "' = " + b + " is outside the plausible range [1e-12, 1e12] (SI units: " + unit +
                     "); check the units");
  }
}

model::Plant ParsePlant(const json& j, const std::string& source, const std::string& where,
                 bool is_std) {
  if (!j.is_object()) Fail(source, "'" + (where.empty() ? "(top level)" : where) + "' must be an object");
  model::Plant p;
  p.m = Number(j, "m", source, where, is_std);
  p.b = Number(j, "b", source, where, is_std);
  auto modes = j.find("modes");
  if (modes == j.end()) Fail(source, "missing key '" + where + "modes' (use [] for the rigid body alone)");
  if (!modes->is_array()) Fail(source, "key '" + where + "modes' must be an array");
  if (modes->size() > kMaxModes) {
    Fail(source, "key '" + where + "modes' has " + std::to_string(modes->size()) + " entries, more than " +
                     std::to_string(kMaxModes) + " (the most zwidth handles)");
  }
  for (size_t i = 0; i < modes->size(); ++i) {
    const json& mj = (*modes)[i];
    const std::string w = where + "modes[" + std::to_string(i) + "].";
    if (!mj.is_object()) Fail(source, "'" + w.substr(0, w.size() - 1) + "' must be an object");
    CheckKeys(mj, {"omega", "c", "v", "d"}, source, w);
    p.modes.push_back({Number(mj, "omega", source, w, is_std), Number(mj, "c", source, w, is_std),
                       Number(mj, "v", source, w, is_std), Number(mj, "d", source, w, is_std)});
  }
  if (is_std) {  // a standard error is >= 0 (inf: null, unknown)
    std::vector<std::pair<std::string, double>> all = {{"m", p.m}, {"b", p.b}};
    for (size_t i = 0; i < p.modes.size(); ++i) {
      const std::string w = "modes[" + std::to_string(i) + "].";
      const model::Mode& md = p.modes[i];
      for (auto [k, v] : {std::pair{"omega", md.omega}, {"c", md.c}, {"v", md.v}, {"d", md.d}}) all.emplace_back(w + k, v);
    }
    for (const auto& [k, v] : all) {
      if (v < 0.0) Fail(source, "key '" + where + k + "' is a standard error and must be >= 0 (null: unknown)");
    }
  }
  if (!is_std) {
    CheckPlausible(p.m, source, where + "m");
    CheckPlausible(p.b, source, where + "b");
    for (size_t i = 0; i < p.modes.size(); ++i) {
      const std::string w = where + "modes[" + std::to_string(i) + "].";
      const model::Mode& md = p.modes[i];
      CheckPlausible(md.omega, source, w + "omega");
      CheckPlausible(md.c, source, w + "c");
      CheckPlausible(md.v, source, w + "v");
      CheckPlausible(md.d, source, w + "d");
    }
  }
  return p;
}

json NumberOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

const char* const kFrictionKeys[] = {"coulomb_pos", "coulomb_neg", "offset", "breakaway_pos", "breakaway_neg"};

double* FrictionField(model::Friction& f, int i) {
  double* fields[] = {&f.coulomb_pos, &f.coulomb_neg, &f.offset, &f.breakaway_pos, &f.breakaway_neg};
  return fields[i];
}

// "friction" or "std.friction": every key optional (0 when absent; null, in
// the std only, = unknown).
model::Friction ParseFriction(const json& j, const std::string& source, const std::string& where, bool is_std) {
  if (!j.is_object()) Fail(source, "'" + where + "' must be an object");
  CheckKeys(j, {"coulomb_pos", "coulomb_neg", "offset", "breakaway_pos", "breakaway_neg"}, source, where + ".");
  model::Friction f;
  for (int i = 0; i < 5; ++i) {
    if (j.contains(kFrictionKeys[i])) *FrictionField(f, i) = Number(j, kFrictionKeys[i], source, where + ".", is_std);
  }
  std::string why;
  if (!is_std && !f.IsValid(&why)) Fail(source, "invalid '" + where + "': " + why);
  return f;
}

json FrictionToJson(model::Friction f) {
  json j = json::object();
  for (int i = 0; i < 5; ++i) j[kFrictionKeys[i]] = NumberOrNull(*FrictionField(f, i));
  return j;
}

json PlantToJson(const model::Plant& p) {
  json j;
  j["m"] = NumberOrNull(p.m);
  j["b"] = NumberOrNull(p.b);
  j["modes"] = json::array();
  for (const model::Mode& md : p.modes) {
    j["modes"].push_back({{"omega", NumberOrNull(md.omega)}, {"c", NumberOrNull(md.c)},
                          {"v", NumberOrNull(md.v)}, {"d", NumberOrNull(md.d)}});
  }
  return j;
}

}  // namespace

// Also names NaN and Infinity outside strings: Python's json.dump writes them
// (allow_nan=True by default), and nlohmann's "syntax error ... truncated or
// malformed" hid the real problem.
void CheckJsonDepth(const std::string& text, const std::string& source, int max_depth) {
  int depth = 0;
  bool in_string = false;
  size_t line = 1;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if ((c == 'N' && text.compare(i, 3, "NaN") == 0) || (c == 'I' && text.compare(i, 8, "Infinity") == 0)) {
      throw InputError(source + ": line " + std::to_string(line) + ": " + (c == 'N' ? "NaN" : "Infinity") +
                       " is not a JSON number (Python's json.dump writes it unless allow_nan=False): give a "
                       "finite number");
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        throw InputError(source + ": line " + std::to_string(line) + ": JSON nested deeper than " +
                         std::to_string(max_depth) + " levels; a model or scene file is never that deep");
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

void CheckNotJsonOfAnotherKind(const std::string& text, const std::string& source, const std::string& what,
                               const std::string& command) {
  const std::string takes = command + " takes a " + what + " JSON";
  const std::string make = what == "model" ? " (make one from a log with `zwidth fit LOG -o MODEL.json`)"
                                           : " ({\"objects\": [{\"name\": ..., \"K\": ..., \"B\": ...}]})";
  for (size_t off : {0, 512, 1024, 2048}) {
    if (text.size() >= off + 8 && text.compare(off, 8, "\x89HDF\r\n\x1a\n") == 0) {
      throw InputError(source + ": not a " + what + " JSON: this is an HDF5 file (a log, or a frequency response "
                       "saved by `zwidth estimate`; fit and estimate take those); " + takes + make);
    }
  }
  if (text.rfind("MATLAB", 0) == 0) {
    throw InputError(source + ": not a " + what + " JSON: this is a MATLAB .mat file (a log: fit and estimate take "
                     "it); " + takes + make);
  }
  size_t b = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;  // UTF-8 BOM
  b = text.find_first_not_of(" \t\r\n", b);
  if (b == std::string::npos || text[b] == '{' || text[b] == '[') return;
  const size_t e = text.find_first_of("\r\n", b);
  std::string line = text.substr(b, std::min<size_t>(e == std::string::npos ? text.size() - b : e - b, 60));
  for (char& c : line) if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  const bool frf = line.rfind("f_hz", 0) == 0 || line.rfind("\"f_hz\"", 0) == 0;
  const bool log = line.find_first_of(",;\t") != std::string::npos || line[0] == '#' ||
                   std::isdigit(static_cast<unsigned char>(line[0])) || line[0] == '-';
  if (frf) {
    throw InputError(source + ": not a " + what + " JSON: it starts '" + line + "', a frequency response saved by "
                     "`zwidth estimate` (fit takes it); " + takes + make);
  }
  if (log) {
    throw InputError(source + ": not a " + what + " JSON: it starts '" + line + "', like a text log (fit and "
                     "estimate take logs); " + takes + make);
  }
}

void CheckDuplicateKeys(const std::string& text, const std::string& source) {
  struct Level {
    bool object;
    bool expect_key;
    std::map<std::string, size_t> keys;  // key -> line
  };
  std::vector<Level> stack;
  size_t line = 1;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (c == '"') {
      const size_t start = ++i;
      while (i < text.size() && text[i] != '"') {
        if (text[i] == '\\') ++i;
        ++i;
      }
      if (!stack.empty() && stack.back().object && stack.back().expect_key) {
        const std::string key = text.substr(start, std::min(i, text.size()) - start);
        auto [it, fresh] = stack.back().keys.emplace(key, line);
        if (!fresh) {
          throw InputError(source + ": line " + std::to_string(line) + ": duplicate key '" + key.substr(0, 40) +
                           "' (first at line " + std::to_string(it->second) +
                           "; the last would silently win): remove one");
        }
        stack.back().expect_key = false;
      }
    } else if (c == '{' || c == '[') {
      stack.push_back({c == '{', c == '{', {}});
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();
    } else if (c == ',' && !stack.empty() && stack.back().object) {
      stack.back().expect_key = true;
    }
  }
}

std::string ReadSmallFile(const std::string& path, const std::string& what, size_t max_bytes) {
  CheckInputFile(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open " + what + " (does it exist?)");
  std::string text;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      throw InputError(path + ": the " + what + " is larger than " + std::to_string(max_bytes >> 20) +
                       " MiB, more than such a file holds");
    }
  }
  if (in.bad()) throw InputError(path + ": read error");
  return text;
}

std::string SamplePeriodProblem(double T, const std::string& name) {
  if (T >= kMinPeriodS && T <= kMaxPeriodS) return "";
  std::ostringstream os;
  os.precision(6);
  os << name << " = " << T << " s: a sample period must lie in [1e-06, 0.1] s (a rate of 10 Hz..1 MHz); " << name
     << " is the period T in seconds";
  const bool rate = T >= 10.0 && T <= 1e6, ms = T > 0.1 && T <= 100.0;
  // A flag or a caller's argument (ModelPeriod::period_s) is passed, a file's field written.
  const bool passed = name.rfind("--", 0) == 0 || name.find("::") != std::string::npos;
  const std::string give = passed ? "pass " + name + " " : "write ";
  if (rate) os << ", not the rate: for " << T << " Hz " << give << 1.0 / T;
  if (ms) os << (rate ? "; " : ": ") << "for " << T << " ms " << give << T * 1e-3;
  return os.str();
}

ModelFile ParseModelJson(const std::string& text, const std::string& source) {
  CheckJsonDepth(text, source);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e999
    Fail(source, std::string("not valid JSON (truncated or malformed): ") + e.what());
  }
  CheckDuplicateKeys(text, source);  // valid JSON: nlohmann kept the last of a repeated key
  if (!j.is_object()) Fail(source, "top level must be a JSON object");
  CheckKeys(j, {"m", "b", "modes", "delay_samples", "sample_period_s", "name", "std", "fit", "covariance",
                "friction", "format_version", "provenance", "units", "encoder_step"},
            source, "");
  if (auto it = j.find("format_version"); it != j.end()) {
    if (!it->is_number_integer() || it->get<std::int64_t>() < 1) {
      Fail(source, "key 'format_version' must be a whole number >= 1, got " + it->dump());
    }
    if (it->get<std::int64_t>() > kModelFormatVersion) {
      Fail(source, "format_version " + it->dump() + " is newer than this zwidth reads (" +
                       std::to_string(kModelFormatVersion) + "): upgrade zwidth, or re-export the model with the "
                       "zwidth that wrote it");
    }
  }
  if (auto it = j.find("provenance"); it != j.end() && !it->is_object()) Fail(source, "'provenance' must be an object");
  ModelFile mf;
  mf.plant = ParsePlant(j, source, "", false);
  if (auto it = j.find("delay_samples"); it != j.end()) {
    if (!it->is_number_integer()) Fail(source, "key 'delay_samples' must be an integer, got " + it->dump());
    // Range-checked as a 64-bit value before narrowing: 4294967298 is not 2.
    const bool negative = it->is_number_integer() && !it->is_number_unsigned() && it->get<std::int64_t>() < 0;
    if (negative || it->get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxDelaySamples)) {
      Fail(source, "key 'delay_samples' = " + it->dump() + " is outside [0, " + std::to_string(kMaxDelaySamples) +
                       "] samples");
    }
    mf.plant.delay_samples = static_cast<int>(it->get<std::int64_t>());
  }
  if (auto it = j.find("name"); it != j.end()) {
    if (!it->is_string()) Fail(source, "key 'name' must be a string");
    mf.plant.name = it->get<std::string>();
  }
  if (auto it = j.find("units"); it != j.end()) {
    if (!it->is_string() || (*it != "rotary" && *it != "linear")) {
      Fail(source, "key 'units' must be \"rotary\" or \"linear\", got " + it->dump().substr(0, 40));
    }
    mf.linear = *it == "linear";
  }
  if (j.contains("sample_period_s")) {
    const double t = Number(j, "sample_period_s", source, "");
    if (const std::string why = SamplePeriodProblem(t, "key 'sample_period_s'"); !why.empty()) Fail(source, why);
    mf.sample_period_s = t;
  }
  if (j.contains("encoder_step")) {
    const double q = Number(j, "encoder_step", source, "");
    if (!(q >= kPlausibleMin && q <= kMaxEncoderStep)) {
      char b[64];
      std::snprintf(b, sizeof b, "%g", q);
      Fail(source, std::string("key 'encoder_step' = ") + b + " is outside [1e-12, 1] (rad or m per count): remove "
                       "the key when the encoder step is not known");
    }
    mf.encoder_step = q;
  }
  if (auto it = j.find("std"); it != j.end()) {
    mf.std_errors = ParsePlant(*it, source, "std.", true);
    CheckKeys(*it, {"m", "b", "modes", "friction"}, source, "std.");
    if (auto f = it->find("friction"); f != it->end()) {
      if (!j.contains("friction")) Fail(source, "'std.friction' is given but 'friction' is not");
      mf.friction_std = ParseFriction(*f, source, "std.friction", true);
    }
    if (mf.std_errors->modes.size() != mf.plant.modes.size()) {
      Fail(source, "'std.modes' has " + std::to_string(mf.std_errors->modes.size()) +
                       " entries but 'modes' has " + std::to_string(mf.plant.modes.size()));
    }
  }
  if (auto it = j.find("friction"); it != j.end()) mf.friction = ParseFriction(*it, source, "friction", false);
  if (auto it = j.find("fit"); it != j.end()) mf.fit = *it;
  std::string why;
  if (!mf.plant.IsValid(&why)) Fail(source, "invalid parameter: " + why);
  if (auto it = j.find("covariance"); it != j.end()) {
    if (!it->is_object()) Fail(source, "'covariance' must be an object");
    CheckKeys(*it, {"space", "parameters", "matrix"}, source, "covariance.");
    if (!it->contains("space") || (*it)["space"] != "log") Fail(source, "'covariance.space' must be \"log\"");
    const std::vector<std::string> names = stability::LogParameterNames(mf.plant);
    if (!it->contains("parameters") || (*it)["parameters"] != json(names)) {
      Fail(source, "'covariance.parameters' must be " + json(names).dump() + " for this model");
    }
    const json& mj = (*it)["matrix"];
    const size_t p = names.size();
    if (!mj.is_array() || mj.size() != p) Fail(source, "'covariance.matrix' must be " + std::to_string(p) + " rows");
    for (size_t r = 0; r < p; ++r) {
      if (!mj[r].is_array() || mj[r].size() != p) {
        Fail(source, "'covariance.matrix[" + std::to_string(r) + "]' must have " + std::to_string(p) + " numbers");
      }
      for (size_t c = 0; c < p; ++c) {
        if (!mj[r][c].is_number()) Fail(source, "'covariance.matrix[" + std::to_string(r) + "][" + std::to_string(c) + "]' must be a number");
        mf.log_covariance.push_back(mj[r][c].get<double>());
      }
    }
    try {
      stability::CheckLogCovariance(mf.plant, mf.log_covariance);
    } catch (const InputError& e) {
      Fail(source, std::string("'covariance': ") + e.what());
    }
  }
  return mf;
}

ModelFile ReadModelJson(const std::string& path) { return ReadModelJsonFor(path, "this command"); }

ModelFile ReadModelJsonFor(const std::string& path, const std::string& command) {
  const std::string text = ReadSmallFile(path, "model file", kMaxJsonBytes);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    throw InputError(path + ": empty model file");
  }
  CheckNotJsonOfAnotherKind(text, path, "model", command);
  return ParseModelJson(text, path);
}

std::string ConvertDelayToPeriod(ModelFile* mf, double T, const std::string& what) {
  if (!mf->sample_period_s || mf->plant.delay_samples == 0) return "";
  const double Tm = *mf->sample_period_s;
  if (std::abs(Tm - T) <= 1e-12 * T) return "";
  const int d = mf->plant.delay_samples;
  const double q = d * Tm / T;
  char buf[400];
  const bool whole = std::abs(q - std::round(q)) <= 1e-9 * std::max(1.0, q);
  if (whole && std::round(q) > kMaxDelaySamples) {
    std::snprintf(buf, sizeof buf, "%s's input delay of %d samples of %g s is %.0f samples at the period %g s, more "
                  "than %d", what.c_str(), d, Tm, q, T, kMaxDelaySamples);
    throw InputError(buf);
  }
  if (whole) {
    const int dn = static_cast<int>(std::round(q));
    std::snprintf(buf, sizeof buf,
                  "%s's input delay is %d samples of its sample_period_s %g s (%g s): %d samples at the "
                  "period %g s used here", what.c_str(), d, Tm, d * Tm, dn, T);
    mf->plant.delay_samples = dn;
    mf->sample_period_s = T;
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "%s's input delay is %d samples of its sample_period_s %g s (%g s), which is %.6g samples at "
                "the period %g s: a delay of a fraction of a sample cannot be kept; re-fit the model from a log "
                "at that rate, or edit its delay_samples (and sample_period_s) if you mean another delay",
                what.c_str(), d, Tm, d * Tm, q, T);
  throw InputError(buf);
}

double ResolveModelPeriod(std::optional<double> period_s, ModelFile* mf, std::string* note) {
  note->clear();
  if (!period_s) return mf->sample_period_s ? *mf->sample_period_s : 0.001;
  const std::string why = SamplePeriodProblem(*period_s, "ModelPeriod::period_s");
  if (!why.empty()) throw InputError(why);
  *note = ConvertDelayToPeriod(mf, *period_s, "the model");
  return *period_s;
}

bool ParseUnitsWord(const std::string& word, const std::string& name) {
  if (word == model::kRotaryUnits.word) return false;
  if (word == model::kLinearUnits.word) return true;
  throw InputError(name + " '" + word.substr(0, 20) + "' is not one of rotary (kg m^2, N m s/rad), linear (kg, N s/m)");
}

json ModelToJson(const ModelFile& mf) {
  json j;
  j["format_version"] = kModelFormatVersion;
  if (!mf.plant.name.empty()) j["name"] = mf.plant.name;
  json p = PlantToJson(mf.plant);
  j["m"] = p["m"];
  j["b"] = p["b"];
  j["modes"] = p["modes"];
  j["delay_samples"] = mf.plant.delay_samples;
  if (mf.linear) j["units"] = model::kLinearUnits.word;  // absent: rotary (files of rotary models unchanged)
  if (mf.sample_period_s) j["sample_period_s"] = *mf.sample_period_s;
  if (mf.encoder_step) j["encoder_step"] = *mf.encoder_step;
  if (mf.std_errors) j["std"] = PlantToJson(*mf.std_errors);
  if (mf.friction) {
    j["friction"] = FrictionToJson(*mf.friction);
    if (mf.friction_std && mf.std_errors) j["std"]["friction"] = FrictionToJson(*mf.friction_std);
  }
  if (!mf.log_covariance.empty()) {
    const size_t p = static_cast<size_t>(stability::NumLogParameters(mf.plant));
    json rows = json::array();
    for (size_t r = 0; r < p; ++r) {
      json row = json::array();
      for (size_t c = 0; c < p; ++c) row.push_back(mf.log_covariance.at(r * p + c));
      rows.push_back(row);
    }
    j["covariance"] = {{"space", "log"}, {"parameters", stability::LogParameterNames(mf.plant)}, {"matrix", rows}};
  }
  if (!mf.fit.is_null()) j["fit"] = mf.fit;
  return j;
}

void WriteModelJson(const std::string& path, const ModelFile& mf) {
  // A model with a NaN or inf parameter would be written as null and refused
  // when read back: it is a failed computation, not an output.
  const model::Plant& p = mf.plant;
  bool finite = std::isfinite(p.m) && std::isfinite(p.b);
  for (const model::Mode& md : p.modes) {
    finite = finite && std::isfinite(md.omega) && std::isfinite(md.c) && std::isfinite(md.v) && std::isfinite(md.d);
  }
  if (mf.friction) finite = finite && mf.friction->IsValid(nullptr);
  if (!finite) throw ComputationError("the model has a non-finite parameter; '" + path + "' was not written");
  json j = ModelToJson(mf);
  j["provenance"] = ProvenanceJson();
  WriteTextAtomically(path, j.dump(2) + "\n");
}

}  // namespace zwidth::io
