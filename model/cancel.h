// Stopping a long computation from outside (the Python module's Ctrl-C).
//
// Long loops (a fit's starts, the Z-width scans and summaries, Monte Carlo
// draws, relay simulations, every ParallelFor item) call PollCancel() once per
// step. Without a check installed (the CLI: SIGINT ends the process) it is one
// relaxed atomic load. With one, the installing host's check runs at most every
// kCancelPollSeconds per thread; when it says stop, every thread's next
// PollCancel throws Cancelled until ClearCancel(), so a ParallelFor stops all
// its threads and rethrows it. Results are never half-made: Cancelled unwinds
// like any error (nothing is written before a computation ends).
#pragma once

#include <exception>

namespace zwidth {

struct Cancelled : std::exception {
  const char* what() const noexcept override { return "interrupted"; }
};

// Returns true to stop. Thread-safe and cheap; may be called from any thread
// (a host whose check only works on one thread returns false on the others).
using CancelCheck = bool (*)();
inline constexpr double kCancelPollSeconds = 0.02;

void SetCancelCheck(CancelCheck check);  // nullptr: none
void PollCancel();                       // throws Cancelled
void ClearCancel();                      // after the host has reported the stop
bool CancelRequested();

}  // namespace zwidth
