// The haptic loop's options (stability/loop_options.h) from command-line and
// file text: velocity-filter coefficients and a hand.
#pragma once

#include <string>

#include "stability/loop_options.h"

namespace zwidth::io {

// Parses "b:b0,b1,...;a:a0,a1,..." (a0 must be 1). Throws InputError naming
// the problem. `what` names the source in messages (a flag or a file path).
void ParseFilterCoefficients(const std::string& text, const std::string& what, stability::LoopOptions* loop);

// "M,B,K" in SI; throws InputError (negative or non-finite values, not three numbers).
stability::Hand ParseHand(const std::string& text);

}  // namespace zwidth::io
