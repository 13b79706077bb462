#include "apps/common.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <sstream>

#include "io/frf_file.h"
#include "io/model_json.h"
#include "io/provenance.h"
#include "io/option_names.h"
#include "io/printable.h"
#include "model/error.h"

namespace zwidth::app {

// The table of fields, flags and keywords is io/option_names.cc (shared with the Python module).
std::string WithFlags(const std::string& message) { return io::WithFlags(message); }

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

CLI::Option* AddSeedOption(CLI::App* cmd, std::uint64_t* seed, const std::string& help) {
  const CLI::Validator whole(
      [](std::string& s) -> std::string {
        std::uint64_t v = 0;
        // Digits only (no sign, no fraction); from_chars refuses what does not fit 64 bits.
        if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos ||
            std::from_chars(s.data(), s.data() + s.size(), v).ec != std::errc()) {
          return "must be a whole number from 0 to 18446744073709551615 (a random seed), got '" + s.substr(0, 40) + "'";
        }
        return "";
      },
      "SEED");
  return cmd->add_option("--seed", *seed, help)->check(whole)->capture_default_str();
}

std::string JoinPaths(const std::vector<std::string>& paths) {
  std::string s;
  for (const auto& p : paths) s += (s.empty() ? "" : " + ") + p;
  return s;
}

// The library's estimate (analysis/logs_estimate.h); its notes on stderr, in the CLI's words.
LogsEstimate EstimateFromLogs(const std::vector<std::string>& paths, const EstimateFlags& flags, bool for_fit) {
  return analysis::EstimateFromLogs(paths, flags.Options(for_fit), [](const std::string& line) {
    std::fprintf(stderr, "%s\n", io::Printable(WithFlags(line)).c_str());
  });
}

double StageTimer::Lap(const std::string& stage) {
  const auto now = std::chrono::steady_clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
  if (enabled_) std::fprintf(stderr, "  %-28s %9.3f ms\n", stage.c_str(), ms);
  start_ = now;
  return ms;
}

double ResolvePeriod(double flag, io::ModelFile* mf) {
  std::string note;
  const double T = io::ResolveModelPeriod(Given(flag), mf, &note);
  if (!note.empty()) std::fprintf(stderr, "note: %s\n", WithFlags(note).c_str());
  return T;
}

void ConvertDelayToPeriod(io::ModelFile* mf, double T, const std::string& what) {
  const std::string note = io::ConvertDelayToPeriod(mf, T, what);
  if (!note.empty()) std::fprintf(stderr, "note: %s\n", note.c_str());
}

namespace {
std::string& StoredCommandLine() {
  static std::string line;
  return line;
}
}  // namespace

void SetCommandLine(int argc, char** argv) {
  std::string& line = StoredCommandLine();
  line.clear();
  for (int i = 0; i < argc; ++i) {
    const std::string a = i == 0 ? "zwidth" : argv[i];
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                         "0123456789-_./=:,+@%") == std::string::npos;
    std::string q = a;
    if (!plain) {
      q = "'";
      for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
      q += "'";
    }
    line += (i ? " " : "") + q;
  }
  io::SetInvocation(line);  // the provenance of every JSON file written (io/provenance.h)
}

const std::string& CommandLine() { return StoredCommandLine(); }

}  // namespace zwidth::app
