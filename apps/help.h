// How the command line presents itself: option groups by topic, an example per
// command, and the bash completion script, all from the parser's own option
// lists so that a flag added anywhere in apps/ is grouped and completed here.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace zwidth::app {

// The topic of each option, in the order help prints them. An option found in
// no row of the table (apps/help.cc) stays in CLI11's "Options" group; the
// test tests/cli_help_test.sh fails on such an option, so a new flag gets its
// row.
inline constexpr const char* kHelpTopics[] = {
    "Simulation", "Excitation", "Log selection", "Estimate (Welch)", "Fit",
    "Friction and actuator", "Comparison", "Loop and stability", "Uncertainty", "Validation", "Output",
};

// Call once, after every subcommand has been added: puts each option in its
// topic, sets each command's footer (examples) and a formatter that prints the
// topics in the order above and the footers also in --help-all. Adds
// --help-all and two hidden flags the build uses: --bash-completion (prints
// BashCompletion) and --help-man (prints ManText, for help2man).
void OrganizeHelp(CLI::App& app);

// The text help2man turns into the man page: the top-level help, then a
// section "*zwidth COMMAND*" per command with its help, its option topics as
// subsections and its examples as "$ zwidth ..." lines.
std::string ManText(const CLI::App& app);

// A bash completion script for the command: subcommands, every option of each
// (short and long names), a value's choices where the table lists them, else
// file names. Generated from `app`'s own option lists.
std::string BashCompletion(const CLI::App& app);

}  // namespace zwidth::app
