// Milliseconds between laps, for the stage times that analysis::Analyse and
// report::WriteRunReport return.
#pragma once

#include <chrono>

namespace zwidth::analysis {

class Laps {
 public:
  double Lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace zwidth::analysis
