#include "io/model_json.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "io/atomic_file.h"
#include "model/error.h"
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

Plant ParsePlant(const json& j, const std::string& source, const std::string& where,
                 bool is_std) {
  if (!j.is_object()) Fail(source, "'" + (where.empty() ? "(top level)" : where) + "' must be an object");
  Plant p;
  p.m = Number(j, "m", source, where, is_std);
  p.b = Number(j, "b", source, where, is_std);
  auto modes = j.find("modes");
  if (modes == j.end()) Fail(source, "missing key '" + where + "modes' (use [] for the rigid body alone)");
  if (!modes->is_array()) Fail(source, "key '" + where + "modes' must be an array");
  for (size_t i = 0; i < modes->size(); ++i) {
    const json& mj = (*modes)[i];
    const std::string w = where + "modes[" + std::to_string(i) + "].";
    if (!mj.is_object()) Fail(source, "'" + w.substr(0, w.size() - 1) + "' must be an object");
    CheckKeys(mj, {"omega", "c", "v", "d"}, source, w);
    p.modes.push_back({Number(mj, "omega", source, w, is_std), Number(mj, "c", source, w, is_std),
                       Number(mj, "v", source, w, is_std), Number(mj, "d", source, w, is_std)});
  }
  return p;
}

json NumberOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json PlantToJson(const Plant& p) {
  json j;
  j["m"] = NumberOrNull(p.m);
  j["b"] = NumberOrNull(p.b);
  j["modes"] = json::array();
  for (const Mode& md : p.modes) {
    j["modes"].push_back({{"omega", NumberOrNull(md.omega)}, {"c", NumberOrNull(md.c)},
                          {"v", NumberOrNull(md.v)}, {"d", NumberOrNull(md.d)}});
  }
  return j;
}

}  // namespace

ModelFile ParseModelJson(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e999
    Fail(source, std::string("not valid JSON (truncated or malformed): ") + e.what());
  }
  if (!j.is_object()) Fail(source, "top level must be a JSON object");
  CheckKeys(j, {"m", "b", "modes", "delay_samples", "sample_period_s", "name", "std", "fit", "covariance"},
            source, "");
  ModelFile mf;
  mf.plant = ParsePlant(j, source, "", false);
  if (auto it = j.find("delay_samples"); it != j.end()) {
    if (!it->is_number_integer()) Fail(source, "key 'delay_samples' must be an integer, got " + it->dump());
    mf.plant.delay_samples = it->get<int>();
  }
  if (auto it = j.find("name"); it != j.end()) {
    if (!it->is_string()) Fail(source, "key 'name' must be a string");
    mf.plant.name = it->get<std::string>();
  }
  if (j.contains("sample_period_s")) {
    const double t = Number(j, "sample_period_s", source, "");
    if (t <= 0.0) Fail(source, "key 'sample_period_s' must be > 0");
    mf.sample_period_s = t;
  }
  if (auto it = j.find("std"); it != j.end()) {
    mf.std_errors = ParsePlant(*it, source, "std.", true);
    CheckKeys(*it, {"m", "b", "modes"}, source, "std.");
    if (mf.std_errors->modes.size() != mf.plant.modes.size()) {
      Fail(source, "'std.modes' has " + std::to_string(mf.std_errors->modes.size()) +
                       " entries but 'modes' has " + std::to_string(mf.plant.modes.size()));
    }
  }
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

ModelFile ReadModelJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open model file (does it exist?)");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    throw InputError(path + ": empty model file");
  }
  return ParseModelJson(text, path);
}

json ModelToJson(const ModelFile& mf) {
  json j;
  if (!mf.plant.name.empty()) j["name"] = mf.plant.name;
  json p = PlantToJson(mf.plant);
  j["m"] = p["m"];
  j["b"] = p["b"];
  j["modes"] = p["modes"];
  j["delay_samples"] = mf.plant.delay_samples;
  if (mf.sample_period_s) j["sample_period_s"] = *mf.sample_period_s;
  if (mf.std_errors) j["std"] = PlantToJson(*mf.std_errors);
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
  WriteTextAtomically(path, ModelToJson(mf).dump(2) + "\n");
}

}  // namespace zwidth::io
