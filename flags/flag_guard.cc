// One validator for every number typed on the command line (issue 30).
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>

#include "flags/flag_guard.h"
#include "io/printable.h"
#include "model/error.h"

namespace zwidth::flags {
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

// The long names ("--delays") of the options of `app` and its subcommands
// that split their value at a delimiter.
// And in `valued` the names ("--detrend", "-o") of every option that takes a value.
void ListFlagNames(const CLI::App& app, std::set<std::string>* names, std::set<std::string>* valued) {
  for (const CLI::Option* opt : app.get_options()) {
    if (opt->get_type_size() == 0 || opt->get_positional()) continue;  // a switch, a positional argument
    for (const std::string& n : opt->get_lnames()) valued->insert("--" + n);
    for (const std::string& n : opt->get_snames()) valued->insert("-" + n);
    if (opt->get_delimiter() == '\0') continue;
    for (const std::string& n : opt->get_lnames()) names->insert("--" + n);
  }
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    ListFlagNames(*sub, names, valued);
  }
}

// The 1-based index of the first empty (or blank) item of `value` split at
// ',', or 0 when there is none.
size_t EmptyItem(const std::string& value) {
  size_t item = 1, start = 0;
  for (;; ++item) {
    const size_t end = value.find(',', start);
    const std::string piece = value.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (piece.find_first_not_of(" \t") == std::string::npos) return item;
    if (end == std::string::npos) return 0;
    start = end + 1;
  }
}

}  // namespace

void CheckListFlags(const CLI::App& app, int argc, char** argv) {
  std::set<std::string> names, valued;
  ListFlagNames(app, &names, &valued);
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") return;  // positional arguments follow
    const size_t eq = arg.rfind("--", 0) == 0 ? arg.find('=') : std::string::npos;
    const std::string name = arg.substr(0, eq);
    if (!valued.count(name)) continue;
    if (eq == std::string::npos && i + 1 >= argc) return;  // CLI11 reports the missing value
    const std::string value = eq == std::string::npos ? argv[++i] : arg.substr(eq + 1);
    // An empty value is never a choice: `--detrend ""`, `--time-unit ""`, `--delimiter ""` silently
    // meant the default, `--delays ""` the delay 0. A space or a tab is a value (`--delimiter ' '`,
    // `--delimiter $'\t'`: io/log_text.cc takes both); a blank item of a list is caught below.
    if (value.empty()) {
      throw InputError(name + " '" + io::Printable(value) + "': an empty value; give one (or leave " + name +
                       " out for its default)");
    }
    if (!names.count(name)) continue;
    if (const size_t item = EmptyItem(value)) {
      throw InputError(name + " '" + io::Printable(value) + "': item " + std::to_string(item) +
                       " of the comma-separated list is empty; give a number between each pair of commas "
                       "(e.g. " + name + " 2,4)");
    }
  }
}

CLI::Validator NonZeroWhenGiven() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || x != 0.0) return "";  // non-numbers: CheckNumber and CLI11 name them
        return "'" + v + "' is the value that means \"not given\" (the default); give a positive value or "
               "leave the flag out";
      },
      "", "non-zero");
}

void GuardNumericFlags(CLI::App* app) {
  for (CLI::Option* opt : app->get_options()) {
    const std::string type = opt->get_type_name();
    const bool floating = type == "FLOAT" || type == "NUMBER";
    if (!floating && type != "INT" && type != "UINT") continue;
    opt->check(CLI::Validator([floating](std::string& v) { return CheckNumber(v, floating); }, "", "number"));
  }
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; })) GuardNumericFlags(sub);
}

}  // namespace zwidth::flags
