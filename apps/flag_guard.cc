// One validator for every number typed on the command line (issue 30).
#include <cmath>
#include <cstdlib>
#include <string>

#include "apps/common.h"

namespace zwidth::app {
namespace {

// "" (CLI11 reads it as 0: `--delays ""` was the delay 0), "nan" and "inf"
// (strtod reads them: NaN is how several flags say "not given", so `--period
// nan` silently meant the default) are refused; so is anything strtod does
// not read whole. Integers are left to CLI11's own conversion after this.
std::string CheckNumber(const std::string& value, bool floating) {
  const size_t a = value.find_first_not_of(" \t");
  if (a == std::string::npos) return "an empty value: give a number";
  if (!floating) return "";
  const std::string t = value.substr(a, value.find_last_not_of(" \t") - a + 1);
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size()) return "'" + t + "' is not a number";
  if (!std::isfinite(v)) return "'" + t + "' is not a finite number: give a finite value (omit the flag for its default)";
  return "";
}

}  // namespace

void GuardNumericFlags(CLI::App* app) {
  for (CLI::Option* opt : app->get_options()) {
    const std::string type = opt->get_type_name();
    const bool floating = type == "FLOAT" || type == "NUMBER";
    if (!floating && type != "INT" && type != "UINT") continue;
    opt->check(CLI::Validator([floating](std::string& v) { return CheckNumber(v, floating); }, "", "number"));
  }
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; })) GuardNumericFlags(sub);
}

}  // namespace zwidth::app
