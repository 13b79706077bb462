// The velocity filter F(z) of the haptic loop (stability/loop_options.h): the
// first-order low-pass that filter-sweep and --velocity-filter-hz set. Parsing
// coefficients from text lives in io/loop_text.h; the filter in the time
// domain in stability/velocity_filter_internal.h.
#pragma once

#include "stability/loop_options.h"

namespace zwidth::stability {

// First-order low-pass F = (1 - a)/(1 - a z^-1), a = exp(-2 pi f_c T). Throws
// InputError unless 0 < f_c < 1/(2T).
void SetLowPassFilter(double cutoff_hz, double period_s, LoopOptions* loop);

}  // namespace zwidth::stability
