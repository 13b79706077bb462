// flags/flag_guard.h: the checks every command line gets, on a CLI11 app
// declared here: a number typed as "", "nan", "inf" or "12x" refused naming the
// flag (CLI11 alone reads "" as 0 and strtod reads nan and inf), integers and
// finite numbers accepted; an empty item of a comma-separated list refused with
// its position (CLI11 drops empty items before any check sees them).
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>

#include "flags/flag_guard.h"
#include "model/error.h"

namespace zwidth::flags {
namespace {

struct App {
  CLI::App app{"t"};
  double period = 1e-3;
  int seed = 0;
  std::vector<int> delays;
  App() {
    app.add_option("--period", period);
    app.add_option("--seed", seed);
    app.add_option("--delays", delays)->delimiter(',');
    GuardNumericFlags(&app);
  }
  // "" when accepted, else CLI11's message.
  std::string Parse(std::vector<std::string> args) {
    args.insert(args.begin(), "t");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    try {
      CheckListFlags(app, static_cast<int>(argv.size()), argv.data());
      app.parse(static_cast<int>(argv.size()), argv.data());
    } catch (const CLI::ParseError& e) {
      return std::string("parse: ") + e.what();
    } catch (const InputError& e) {
      return std::string("input: ") + e.what();
    }
    return "";
  }
};

TEST(FlagGuard, NumbersThatAreNotFiniteNumbersAreRefusedByFlag) {
  for (const char* bad : {"", "nan", "inf", "-inf", "12x", " "}) {
    App a;
    const std::string m = a.Parse({"--period", bad});
    EXPECT_NE(m.find("--period"), std::string::npos) << "'" << bad << "': " << m;
  }
  App ok;
  EXPECT_EQ(ok.Parse({"--period", "5e-4", "--seed", "7", "--delays", "2,4"}), "");
  EXPECT_EQ(ok.period, 5e-4);
  EXPECT_EQ(ok.seed, 7);
  EXPECT_EQ(ok.delays, (std::vector<int>{2, 4}));
  App empty_int;
  EXPECT_NE(empty_int.Parse({"--seed", ""}).find("--seed"), std::string::npos);
}

TEST(FlagGuard, AnEmptyListItemIsRefusedWithItsPosition) {
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--delays", "2,,4"},
                                               std::vector<std::string>{"--delays=2,4,"},
                                               std::vector<std::string>{"--delays", ",2"}}) {
    App a;
    const std::string m = a.Parse(args);
    EXPECT_EQ(m.rfind("input: --delays", 0), 0u) << m;
    EXPECT_NE(m.find("is empty"), std::string::npos) << m;
  }
  App a;
  EXPECT_NE(a.Parse({"--delays", "2,,4"}).find("item 2"), std::string::npos);
  App after;
  EXPECT_EQ(after.Parse({"--delays", "3", "--", "2,,4"}).find("input:"), std::string::npos);  // positional, not checked
}

}  // namespace
}  // namespace zwidth::flags
