// Typed errors shared by every module. Two tiers (STYLE.md): a broken internal
// contract is an assertion; bad data or a bad request from a user is an
// InputError (exit code 2), and a computation that cannot produce a usable
// number (a fit that does not converge) is a ComputationError (exit code 1).
#pragma once

#include <stdexcept>
#include <string>

namespace zwidth {

// Bad user input: a file, a field, an option. The message says what, where and
// what to do.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A computation that failed on valid input (non-convergence, singular system).
class ComputationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace zwidth
