// A fit as `zwidth fit` and `run` keep it: fit::FitModel (glog quiet, through
// fit::FitLibrary), the sign / swapped-columns diagnosis of a poor fit, the
// friction fit when asked, and the model file (std, fit record). The one
// place that rule lives: the CLI's `fit`, `run`, `batch` and Python's
// zwidth.run call it. Prints nothing.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fit/fit.h"
#include "fit/friction_fit.h"
#include "ident/welch.h"
#include "io/log.h"
#include "io/model_json.h"

namespace zwidth::analysis {

// The time-domain log that the friction fit reads again (the estimate streams
// it), with the estimate's column selection and Welch options.
struct FrictionInput {
  std::string path;
  io::LogSelect select;
  fit::FrictionFitOptions options;  // welch.window_length 0: the fitted response's window
  // A log in memory (Python's zwidth.Log): read instead of `path`.
  std::optional<io::Log> log;
};

// The word of FrictionFitOptions::model ("none", "auto", "coulomb"); an
// InputError naming the field otherwise.
fit::FrictionModel FrictionModelNamed(const std::string& word);

// The friction fit's input of a fit of `logs` (or of a saved response,
// `frf_file`): the one rule of `fit`, `run` and Python's zwidth.run. One
// time-domain log: that log with the estimate's selection and Welch options
// (window_length 0 is the fitted response's, set by FitToModelFile), also for
// kNone (the friction is then only detected and recorded). Several logs or a
// saved response: none; for kAuto *warning says that friction was not checked,
// and kCoulomb is an InputError naming FrictionFitOptions::model. Reads nothing.
std::optional<FrictionInput> FrictionInputFor(const std::vector<std::string>& logs, bool frf_file,
                                              const io::LogSelect& select, const ident::WelchOptions& welch,
                                              fit::FrictionModel model, std::string* warning);
// The same rule for one log in memory (Python's zwidth.Log): always an input.
FrictionInput FrictionInputFor(io::Log log, const ident::WelchOptions& welch, fit::FrictionModel model);

// How the caller shows the library's texts, which name option fields.
struct FitMessages {
  // A text in the caller's words (io::WithFlags, io::WithKeywords); as is when empty.
  std::function<std::string(const std::string&)> words;
  // Each of the fit's warnings as the library writes it (naming fields), when
  // the fit ends; dropped when empty.
  std::function<void(const std::string&)> warning;
  // The axis's units (io::LinearUnitsOf): the file's "units" and the units
  // the friction fit's message names.
  bool linear = false;
  std::string Words(const std::string& s) const { return words ? words(s) : s; }
};

// Fits and packs the model file (std, fit metrics; every text of its "fit"
// record in messages.words); throws ComputationError when the fit does not
// converge, InputError for a response of too few segments (fit::FitModel; a log
// too short for its window is refused before, by CheckLogLength). With
// `friction`, the friction fit (fit::FitFriction) follows, with the window of
// `frf` unless friction->options.welch.window_length says otherwise: its linear
// part and friction go into the file.
io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, const FitMessages& messages = {},
                             fit::FitResult* result = nullptr, const FrictionInput* friction = nullptr,
                             fit::FrictionFitResult* friction_result = nullptr);

}  // namespace zwidth::analysis
