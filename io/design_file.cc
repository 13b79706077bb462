#include "io/design_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "io/printable.h"
#include "io/reference_models.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

using json = nlohmann::json;

// The line of every key and array element of valid JSON `text`, by path
// ("tolerances", "tolerances[2]", "tolerances[2].min"): nlohmann keeps no
// positions, and a message names the line to look at.
std::map<std::string, int> PathLines(const std::string& text) {
  struct Level {
    bool object;
    std::string path;   // of the container
    std::string key;    // objects: the current key
    int index = 0;      // arrays: the current element
    bool expect_key = true;  // objects: the next string is a key; arrays: the next value starts an element
  };
  std::map<std::string, int> lines;
  std::vector<Level> stack;
  int line = 1;
  auto child = [&](const Level& l) {
    return l.object ? (l.path.empty() ? l.key : l.path + "." + l.key) : l.path + "[" + std::to_string(l.index) + "]";
  };
  auto value_starts = [&] {  // an array's next element starts here
    if (!stack.empty() && !stack.back().object && stack.back().expect_key) {
      stack.back().expect_key = false;
      lines.emplace(child(stack.back()), line);
    }
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') { ++line; continue; }
    if (c == ' ' || c == '\t' || c == '\r' || c == ':') continue;
    if (c == '"') {
      const size_t start = ++i;
      while (i < text.size() && text[i] != '"') i += text[i] == '\\' ? 2 : 1;
      if (!stack.empty() && stack.back().object && stack.back().expect_key) {
        stack.back().key = text.substr(start, std::min(i, text.size()) - start);
        stack.back().expect_key = false;
        lines.emplace(child(stack.back()), line);
      } else {
        value_starts();
      }
    } else if (c == '{' || c == '[') {
      value_starts();
      const std::string path = stack.empty() ? "" : child(stack.back());
      stack.push_back({c == '{', path, "", 0, true});
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();
    } else if (c == ',') {
      if (stack.empty()) continue;
      if (!stack.back().object) ++stack.back().index;
      stack.back().expect_key = true;
    } else {
      value_starts();
    }
  }
  return lines;
}

const std::vector<std::string>& Figures() {
  static const std::vector<std::string> f = {"K_cr_at_zero_B", "K_cr_max", "B_t", "B_max", "B_max_from_zero"};
  return f;
}

// m, b or mode<i>_{omega,c,v,d} with i >= 1.
bool IsParameter(const std::string& p) {
  if (p == "m" || p == "b") return true;
  if (p.rfind("mode", 0) != 0) return false;
  size_t k = 4;
  while (k < p.size() && std::isdigit(static_cast<unsigned char>(p[k]))) ++k;
  if (k == 4 || k > 6 || k >= p.size() || p[k] != '_' || std::stoi(p.substr(4, k - 4)) < 1) return false;
  const std::string f = p.substr(k + 1);
  return f == "omega" || f == "c" || f == "v" || f == "d";
}

}  // namespace

bool IsDesignFile(const std::string& path) {
  std::error_code ec;
  if (path == "table1" || !std::filesystem::is_regular_file(path, ec)) return false;
  try {
    const json j = json::parse(ReadSmallFile(path, "design"));
    return j.is_object() && j.value("format", std::string()) == "zwidth-design";
  } catch (const std::exception&) {
    return false;
  }
}

Design ParseDesign(const std::string& text, const std::string& source, const std::string& folder) {
  CheckJsonDepth(text, source);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(source + ": not valid JSON (truncated or malformed): " + e.what());
  }
  CheckDuplicateKeys(text, source);
  const std::map<std::string, int> lines = PathLines(text);
  auto at = [&](const std::string& path) {
    auto it = lines.find(path);
    return source + (it == lines.end() ? "" : " line " + std::to_string(it->second)) + ", key '" + path + "'";
  };
  if (!j.is_object()) throw InputError(source + ": a design file is a JSON object {\"format\": \"zwidth-design\", ...}");
  const std::set<std::string> top = {"format", "format_version", "name", "model", "tolerances", "comment"};
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!top.count(it.key())) {
      throw InputError(at(it.key()) + ": unknown key (a design has format, format_version, name, model, tolerances, comment)");
    }
  }
  if (j.value("format", json()) != "zwidth-design") {
    throw InputError((j.contains("format") ? at("format") : source + ": no key 'format'") +
                     ": a design file says \"format\": \"zwidth-design\"");
  }
  if (auto v = j.find("format_version"); v != j.end() && !(v->is_number_integer() && v->get<std::int64_t>() == 1)) {
    throw InputError(at("format_version") + ": this zwidth reads design format_version 1");
  }
  Design d;
  if (auto n = j.find("name"); n != j.end()) {
    if (!n->is_string()) throw InputError(at("name") + ": a string");
    d.name = n->get<std::string>();
  }
  const auto m = j.find("model");
  if (m == j.end()) {
    throw InputError(source + ": no key 'model': give \"model\": \"table1\", a model JSON's path, or the model object");
  }
  if (m->is_string()) {
    const std::string name = m->get<std::string>();
    if (name == "table1") {
      d.model = Table1Model();
      d.model_is_table1 = true;
      d.model_name = "table1";
    } else {
      std::filesystem::path p(name);
      if (p.is_relative()) p = std::filesystem::path(folder) / p;
      try {
        d.model = ReadModelJsonFor(p.string(), "the design's model");
      } catch (const InputError& e) {
        throw InputError(at("model") + ": " + e.what());
      }
      d.model_name = p.string();
    }
  } else if (m->is_object()) {
    d.model = ParseModelJson(m->dump(), at("model"));
    d.model_name = source + " key 'model'";
  } else {
    throw InputError(at("model") + ": \"table1\", a model JSON's path, or the model object");
  }
  const auto t = j.find("tolerances");
  if (t == j.end() || !t->is_array() || t->empty()) {
    throw InputError((t == j.end() ? source + ": no key 'tolerances'" : at("tolerances")) +
                     ": a non-empty array of tolerances, e.g. [{\"parameter\": \"m\", \"relative\": 0.15}, "
                     "{\"figure\": \"K_cr_max\", \"delay\": 2, \"min\": 1.2}]");
  }
  std::set<std::string> seen;
  for (size_t i = 0; i < t->size(); ++i) {
    const json& e = (*t)[i];
    const std::string path = "tolerances[" + std::to_string(i) + "]";
    auto key_at = [&](const std::string& k) { return lines.count(path + "." + k) ? at(path + "." + k) : at(path); };
    if (!e.is_object()) throw InputError(at(path) + ": a tolerance is an object {\"parameter\" or \"figure\", ...}");
    const std::set<std::string> keys = {"parameter", "figure", "delay", "min", "max", "relative", "absolute", "comment"};
    for (auto it = e.begin(); it != e.end(); ++it) {
      if (!keys.count(it.key())) {
        throw InputError(key_at(it.key()) + ": unknown key (a tolerance has parameter or figure and delay, then "
                         "min and/or max, or relative, or absolute)");
      }
    }
    DesignTolerance tol;
    tol.where = at(path);
    const bool has_p = e.contains("parameter"), has_f = e.contains("figure");
    if (has_p == has_f) throw InputError(at(path) + ": give one of \"parameter\" (m, b, mode1_omega, ...) or \"figure\" (with \"delay\")");
    if (has_p) {
      const json& p = e["parameter"];
      if (!p.is_string() || !IsParameter(p.get<std::string>())) {
        throw InputError(key_at("parameter") + ": " + Printable(p.dump()) + " is no parameter; give m, b or "
                         "mode<i>_omega, mode<i>_c, mode<i>_v, mode<i>_d (i from 1)");
      }
      if (e.contains("delay")) throw InputError(key_at("delay") + ": a parameter has no delay (only a figure has)");
      tol.column = p.get<std::string>();
    } else {
      const json& f = e["figure"];
      std::string list;
      for (const std::string& x : Figures()) list += (list.empty() ? "" : ", ") + x;
      if (!f.is_string() || std::find(Figures().begin(), Figures().end(), f.get<std::string>()) == Figures().end()) {
        throw InputError(key_at("figure") + ": " + Printable(f.dump()) + " is no Z-width figure; give one of " + list);
      }
      const auto dl = e.find("delay");
      if (dl == e.end() || !dl->is_number_integer() || dl->get<std::int64_t>() < 0 ||
          dl->get<std::int64_t>() > kMaxDelaySamples) {
        throw InputError(key_at("delay") + ": a figure needs \"delay\": the loop's delay in samples, an integer in [0, " +
                         std::to_string(kMaxDelaySamples) + "] that RunOptions::delays computes");
      }
      tol.is_figure = true;
      tol.figure = f.get<std::string>();
      tol.delay = static_cast<int>(dl->get<std::int64_t>());
      tol.column = "d" + std::to_string(tol.delay) + "_" + tol.figure;
    }
    auto number = [&](const char* k, bool positive) -> std::optional<double> {
      const auto it = e.find(k);
      if (it == e.end()) return std::nullopt;
      if (!it->is_number() || !std::isfinite(it->get<double>()) || (positive && !(it->get<double>() > 0))) {
        throw InputError(key_at(k) + ": " + Printable(it->dump()) + " is not a " + (positive ? "positive " : "") +
                         "finite number" + (positive ? std::string(" (") + k + " is a tolerance around the design's value)" : ""));
      }
      return it->get<double>();
    };
    tol.min = number("min", false);
    tol.max = number("max", false);
    tol.relative = number("relative", true);
    tol.absolute = number("absolute", true);
    const int kinds = (tol.min || tol.max) + !!tol.relative + !!tol.absolute;
    if (kinds != 1) {
      throw InputError(at(path) + ": give min and/or max, or relative, or absolute (" +
                       (kinds == 0 ? "none is given" : "more than one kind is given") + ")");
    }
    if (tol.min && tol.max && *tol.min > *tol.max) {
      throw InputError(key_at("max") + ": max is below min; swap them");
    }
    if (!seen.insert(tol.column).second) {
      throw InputError(at(path) + ": a second tolerance on " + tol.column + "; give one per column (min and max in one)");
    }
    d.tolerances.push_back(std::move(tol));
  }
  return d;
}

Design ReadDesign(const std::string& path) {
  const std::string text = ReadSmallFile(path, "design");
  return ParseDesign(text, Printable(path), std::filesystem::path(path).parent_path().string());
}

}  // namespace zwidth::io
