// The checks every command line gets (issue 30): a typed number, a list's items.
#pragma once

#include <CLI/CLI.hpp>

namespace zwidth::flags {

// Adds to every numeric option of `app` and its subcommands (after they are
// declared) the one check of a typed number: an empty value, NaN or an
// infinity is refused naming the flag (exit 2), as are non-numbers.
void GuardNumericFlags(CLI::App* app);
// CLI11 drops the empty items of a delimited list (`--delays 2,,4` read as
// 2,4) before any check sees them, so the command line itself is read first:
// an empty item in the value of any option of `app` (or its subcommands) that
// has a delimiter is an InputError naming the flag and the item.
void CheckListFlags(const CLI::App& app, int argc, char** argv);
// For an option whose 0 means "not given" (--rate: the log's; --window-length:
// the default segment): an explicit 0 is refused instead of silently meaning
// the default (`--counts-per-rev 0` read the output as radians).
CLI::Validator NonZeroWhenGiven();

}  // namespace zwidth::flags
