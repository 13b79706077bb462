// Command-line flags of the haptic loop (issue 16): velocity filter, hands,
// shared by boundary, check and run (and batch, through flags/run_flags.h).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "model/plant.h"
#include "stability/loop_options.h"

namespace zwidth::flags {

struct LoopFlags {
  double filter_hz = std::numeric_limits<double>::quiet_NaN();
  std::string filter_coeffs;
  std::vector<std::string> hands;
};

void AddLoopFlags(CLI::App* cmd, LoopFlags* flags);

// One loop per hand (one loop without a hand when none is given). Throws
// InputError for bad flags (both filter flags, a bad cut-off, unreadable or
// malformed coefficients, a bad hand).
std::vector<stability::LoopOptions> ResolveLoops(const LoopFlags& flags, double period_s);

// True when the loop is the paper's (no filter, no hand).
inline bool IsPlainLoop(const stability::LoopOptions& l) { return !l.HasFilter() && l.hand.IsNone(); }

}  // namespace zwidth::flags
