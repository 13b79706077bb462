// The step of a quantised position: an encoder's count, read from the log.
//
// An encoder's log holds y_i = y_0 + n_i q with integer n_i: every sample
// lies on a grid of step q (rad or m per count). The friction predictions
// need q (stability/friction_prediction.h: the rest-point condition
// K q <= 2 F_c and A* >= 10 q), and a log carries it, so `fit` and `run`
// read it from the log instead of asking.
#pragma once

#include <span>

namespace zwidth::ident {

// q of a position log, or 0 when the samples do not lie on a grid (a
// continuous or noisy position, or one too short or too still to tell).
//
// The candidate is the smallest nonzero step between neighbouring samples
// (an encoder's position changes by whole counts, and a log that stops or
// turns moves by one count somewhere). The counts are summed from the steps
// (each rounded to whole candidates), the step is their least-squares one,
// and it is kept when every sample but 1 in 1000 lies within
// kGridTolerance steps of y_0 + k q (the margin covers a text log's
// rounding: 6 significant digits of 1 rad are 5e-7 rad, 0.003 of the finest
// step tried, 2 pi / 40960), the samples span at least kMinCounts steps and
// at least kMinMoves steps are nonzero. A continuous position fails: the
// rounding of its steps to the candidate adds up as a random walk.
double EncoderStep(std::span<const double> position);

inline constexpr double kGridTolerance = 0.05;  // in steps
inline constexpr int kMinCounts = 8;            // the span of the log, in steps
inline constexpr int kMinMoves = 20;            // nonzero steps between samples

}  // namespace zwidth::ident
