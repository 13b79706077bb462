#include "io/log_units.h"

#include <charconv>
#include <cmath>
#include <numbers>
#include <vector>

#include "model/error.h"

namespace zwidth::io::internal {
namespace {

struct KnownUnit {
  const char* key;  // lower case, without blanks, '.', '*', or a middle dot
  const char* si;
  double scale;
  bool counts = false;
};

constexpr double kDeg = std::numbers::pi / 180.0;

const std::vector<KnownUnit>& InputUnits() {
  static const std::vector<KnownUnit> u = {
      {"nm", "N m", 1.0},     {"mnm", "N m", 1e-3},  {"nmm", "N m", 1e-3}, {"unm", "N m", 1e-6},
      {"\xc2\xb5nm", "N m", 1e-6}, {"ncm", "N m", 1e-2}, {"knm", "N m", 1e3},
      {"n", "N", 1.0},        {"mn", "N", 1e-3},     {"kn", "N", 1e3}};
  return u;
}

const std::vector<KnownUnit>& OutputUnits() {
  static const std::vector<KnownUnit> u = {
      {"rad", "rad", 1.0},     {"mrad", "rad", 1e-3},  {"urad", "rad", 1e-6},   {"deg", "rad", kDeg},
      {"degree", "rad", kDeg}, {"degrees", "rad", kDeg}, {"\xc2\xb0", "rad", kDeg}, {"rev", "rad", 2 * std::numbers::pi},
      {"m", "m", 1.0},         {"cm", "m", 1e-2},      {"mm", "m", 1e-3},       {"um", "m", 1e-6},
      {"\xc2\xb5m", "m", 1e-6}, {"\xce\xbcm", "m", 1e-6}, {"nm", "m", 1e-9},
      {"counts", "", 0, true}, {"count", "", 0, true}, {"cnt", "", 0, true},     {"cnts", "", 0, true},
      {"ticks", "", 0, true},  {"inc", "", 0, true},    {"increments", "", 0, true}, {"pulses", "", 0, true}};
  return u;
}

// Lower case (ASCII), without blanks, '.', '*', '^' and middle dots.
std::string Key(const std::string& s) {
  std::string k;
  for (size_t i = 0; i < s.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c == ' ' || c == '\t' || c == '.' || c == '*' || c == '_' || c == '-') continue;
    if (c == 0xc2 && i + 1 < s.size() && static_cast<unsigned char>(s[i + 1]) == 0xb7) { ++i; continue; }
    if (c == 0xe2 && i + 2 < s.size() && s.compare(i, 3, "\xe2\x8b\x85") == 0) { i += 2; continue; }
    k += static_cast<char>(c < 0x80 ? std::tolower(c) : c);
  }
  return k;
}

const KnownUnit* Find(const std::string& unit, ColumnRole role) {
  const std::string k = Key(unit);
  for (const KnownUnit& u : role == ColumnRole::kInput ? InputUnits() : OutputUnits()) {
    if (k == u.key) return &u;
  }
  return nullptr;
}

std::string KnownList(ColumnRole role) {
  return role == ColumnRole::kInput ? "N m, mN m, N mm, N cm, uN m, kN m, N, mN, kN"
                                    : "rad, mrad, urad, deg, rev, m, cm, mm, um, nm, counts (with LogSelect::counts_per_rev or "
                                      "LogSelect::counts_per_m)";
}

}  // namespace

ColumnUnit ParseColumnUnit(const std::string& written, ColumnRole role, double cpr, double cpm, bool scale_given,
                           const std::string& flag, const std::string& where) {
  std::string unit = written;  // "[N m]" or "(deg)" as a units row may write them
  if (unit.size() >= 2 && ((unit.front() == '[' && unit.back() == ']') || (unit.front() == '(' && unit.back() == ')'))) {
    unit = unit.substr(1, unit.size() - 2);
  }
  const std::string k = Key(unit);
  if (k.empty() || k == "si") return {unit, role == ColumnRole::kInput ? "N m" : "rad", 1.0};
  const KnownUnit* u = Find(unit, role);
  if (u == nullptr && scale_given) {  // the user's scale converts it
    return {unit + ", converted by the scale given", role == ColumnRole::kInput ? "N m" : "rad", 1.0};
  }
  if (u == nullptr) {
    throw InputError(where + ": unit '" + unit.substr(0, 24) + "' is not one zwidth reads for " +
                     (role == ColumnRole::kInput ? "the input (torque or force)" : "the output (position)") + " (" +
                     KnownList(role) + "): convert the column, or pass " + flag + " si with " +
                     (role == ColumnRole::kInput ? "LogSelect::input_scale" : "LogSelect::output_scale") + " to SI");
  }
  if (!u->counts) return {unit, u->si, u->scale, true};
  if (scale_given && cpr == 0 && cpm == 0) return {unit + ", converted by the scale given", "rad", 1.0};
  if (cpr > 0 && cpm > 0) throw InputError(where + ": give LogSelect::counts_per_rev or LogSelect::counts_per_m, not both");
  if (cpr > 0) return {unit, "rad", 2 * std::numbers::pi / cpr};
  if (cpm > 0) return {unit, "m", 1.0 / cpm};
  throw InputError(where + ": the output is in encoder counts ('" + unit.substr(0, 24) +
                   "'): pass LogSelect::counts_per_rev N (a rotary encoder's counts per turn) or LogSelect::counts_per_m N (a linear "
                   "one's), or " + flag + " si with LogSelect::output_scale (rad or m per count)");
}

bool SplitBracketedUnit(const std::string& name, std::string* base, std::string* unit) {
  auto trimmed = [](std::string t) {
    while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.pop_back();
    return t;
  };
  const std::string s = trimmed(name);
  if (base) *base = s;
  if (s.empty() || (s.back() != ']' && s.back() != ')')) return false;
  const size_t open = s.find_last_of(s.back() == ']' ? '[' : '(');
  if (open == std::string::npos || open == 0) return false;
  if (unit) *unit = s.substr(open + 1, s.size() - open - 2);
  if (base) *base = trimmed(s.substr(0, open));
  return true;
}

std::optional<ColumnUnit> UnitOfColumnName(const std::string& name, ColumnRole role, double cpr, double cpm,
                                           bool scale_given, const std::string& flag, const std::string& where) {
  if (std::string unit; SplitBracketedUnit(name, nullptr, &unit)) {
    return ParseColumnUnit(unit, role, cpr, cpm, scale_given, flag, where + " (unit in its name '" + name.substr(0, 40) + "')");
  }
  std::string s = name;
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
  const size_t sep = s.find_last_of("_- ");
  if (sep == std::string::npos || sep == 0 || sep + 1 >= s.size()) return std::nullopt;
  if (Find(s.substr(sep + 1), role) == nullptr) return std::nullopt;
  return ParseColumnUnit(s.substr(sep + 1), role, cpr, cpm, scale_given, flag, where + " (unit in its name '" + name.substr(0, 40) + "')");
}

bool LooksLikeUnit(const std::string& text) {
  std::string s = text;
  if (s.size() >= 2 && (s.front() == '[' || s.front() == '(')) s = s.substr(1, s.size() - 2);
  const std::string k = Key(s);
  return k == "s" || k == "ms" || k == "us" || k == "si" || Find(s, ColumnRole::kInput) != nullptr ||
         Find(s, ColumnRole::kOutput) != nullptr;
}

bool ParseDecimalComma(std::string_view f, double* v) {
  if (f.size() > 64 || f.find('.') != std::string_view::npos) return false;
  char buf[65];
  size_t n = 0;
  for (char c : f) buf[n++] = c == ',' ? '.' : c;
  const char* b = buf;
  if (n > 0 && buf[0] == '+') ++b;
  if (b == buf + n) return false;
  auto [p, ec] = std::from_chars(b, buf + n, *v);
  return ec == std::errc() && p == buf + n;
}

}  // namespace zwidth::io::internal
