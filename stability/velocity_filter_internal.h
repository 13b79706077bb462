// The velocity filter of the haptic loop in the time domain, shared by the
// relay (stability/relay.cc) and the wall simulation (stability/wall_simulation.cc).
#pragma once

#include <algorithm>
#include <vector>

#include "stability/loop_options.h"

namespace zwidth::stability::internal {

// The velocity filter F(z) of LoopOptions in direct form I: w_k = sum b_i v_{k-i}
// - sum_{i>=1} a_i w_{k-i} (a0 = 1). Without coefficients it passes v unchanged.
class VelocityFilter {
 public:
  explicit VelocityFilter(const LoopOptions& loop)
      : b_(loop.filter_b), a_(loop.filter_a), v_(b_.size(), 0.0), w_(a_.size(), 0.0) {}
  double Step(double v) {
    if (b_.empty()) return v;
    std::rotate(v_.rbegin(), v_.rbegin() + 1, v_.rend());
    v_[0] = v;
    double w = 0.0;
    for (size_t i = 0; i < b_.size(); ++i) w += b_[i] * v_[i];
    for (size_t i = 1; i < a_.size(); ++i) w -= a_[i] * w_[i - 1];
    if (!w_.empty()) {
      std::rotate(w_.rbegin(), w_.rbegin() + 1, w_.rend());
      w_[0] = w;
    }
    return w;
  }

 private:
  std::vector<double> b_, a_, v_, w_;  // v_[i] = v_{k-i}, w_[i] = w_{k-1-i} before the step
};

}  // namespace zwidth::stability::internal
