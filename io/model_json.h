// Model files: JSON with SI units and rad/s,
//   {"m": 1.168e-3, "b": 0.00584,
//    "modes": [{"omega": 479.166, "c": 83, "v": 417.612, "d": 80}, ...],
//    "delay_samples": 0, "sample_period_s": 0.001, "name": "...",
//    "std": {"m": ..., "b": ..., "modes": [...]},   // fitted models only
//    "covariance": {"space": "log", "parameters": ["m", "b", "modes[0].omega",
//                   "modes[0].c", "modes[0].v", "modes[0].d", ...],
//                   "matrix": [[...], ...]},          // fitted models only: the full
//      covariance of the natural logs of the SI parameters (relative units),
//      in the order of "parameters" (stability/uncertainty.h)
//    "friction": {"coulomb_pos": 0.008, "coulomb_neg": 0.008, "offset": 0,
//                 "breakaway_pos": 0, "breakaway_neg": 0},   // optional (model/friction.h);
//      its std in "std.friction" (same keys, null = unknown), and the friction's
//      parameters are not in "covariance" (which stays the linear part's)
//    "fit": {...},                                    // fit metrics, free form
//    "format_version": 1,                             // kModelFormatVersion
//    "provenance": {...}}                             // io/provenance.h (files only)
// Any other key is an error, so that a typo cannot pass silently. The schema:
// docs/schema/model.schema.json. A file without "format_version" (written
// before it existed) is read as version 1, whose keys it has; a larger
// version is refused (written by a newer zwidth).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/friction.h"
#include "model/plant.h"
#include "model/simulate.h"

namespace zwidth::io {

struct ModelFile {
  model::Plant plant;
  // Standard errors, same shape as plant (fields may be +inf = unknown).
  std::optional<model::Plant> std_errors;
  std::optional<double> sample_period_s;
  // Coulomb friction and offset identified with (or given beside) the linear
  // plant; absent = a linear-only model. The plant is then the linear part.
  std::optional<model::Friction> friction;
  std::optional<model::Friction> friction_std;  // fields +inf = unknown
  // (2 + 4 N)^2 row-major covariance of the log parameters; empty = none.
  std::vector<double> log_covariance;
  nlohmann::json fit;  // null when absent
  // The axis's units (model/units.h): "units": "linear" in the file (kg,
  // N s/m, m); absent or "rotary": kg m^2, N m s/rad, rad. Every label that
  // reads the model follows it.
  bool linear = false;
  // The position's quantum (rad or m per encoder count) read from the log
  // the model was fitted on (ident::EncoderStep), "encoder_step" in the file;
  // absent: not known (a continuous or noisy position, a saved response,
  // several logs that disagree). The friction predictions use it
  // (analysis::FrictionAmplitudeOptions::encoder_step) unless told another.
  std::optional<double> encoder_step;
};

// "rotary" -> false, "linear" -> true; another word: InputError naming `name`
// (the flag or keyword the caller read it from: "--units", "units").
bool ParseUnitsWord(const std::string& word, const std::string& name);

// The version of the model file's format that this zwidth writes and reads.
inline constexpr int kModelFormatVersion = 1;

// Limits of a model file, refused with an InputError naming the key:
inline constexpr size_t kMaxModes = 64;            // entries of "modes"
inline constexpr int kMaxDelaySamples = model::kMaxDelaySamples;  // "delay_samples" in [0, this]
inline constexpr double kPlausibleMin = 1e-12;     // m, b, omega, c, v, d in
inline constexpr double kPlausibleMax = 1e12;      //   [min, max] (SI, rad/s)
inline constexpr int kMaxJsonDepth = 64;           // nesting of [ and { (anywhere, "fit" too)
inline constexpr size_t kMaxJsonBytes = 64u << 20; // size of a model or scene file
// A sample period, from a model's "sample_period_s" or a --period flag, lies
// in [kMinPeriodS, kMaxPeriodS] s: the rates a log may have, 10 Hz..1 MHz.
inline constexpr double kMinPeriodS = 1e-6, kMaxPeriodS = 0.1;
// A model's "encoder_step" lies in [kPlausibleMin, kMaxEncoderStep] (rad or m
// per count); a fit stores a step read from its log only there.
inline constexpr double kMaxEncoderStep = model::kMaxEncoderStep;

// "" when T lies in that range, else the message naming `name` ("--period",
// "key 'sample_period_s'") with the likely slip (a rate or milliseconds typed
// for a period in s) and the value to give instead.
std::string SamplePeriodProblem(double T, const std::string& name);

// InputError when `text` nests arrays/objects deeper than max_depth: checked
// by a scan of the brackets (outside strings) before nlohmann parses, whose
// parser, copies and error paths recurse once per level.
void CheckJsonDepth(const std::string& text, const std::string& source, int max_depth = kMaxJsonDepth);

// The whole content of a small input file (a model, a scene): a regular file
// (CheckInputFile) of at most max_bytes.
std::string ReadSmallFile(const std::string& path, const std::string& what, size_t max_bytes = kMaxJsonBytes);

// Parses and validates; throws InputError naming the file and the key.
ModelFile ParseModelJson(const std::string& text, const std::string& source);
ModelFile ReadModelJson(const std::string& path);
// The same; `command` names what takes the model in the message when the file
// is of another kind (an HDF5 or .mat file, a text log, a saved frequency
// response). Not an overload: Python binds &ReadModelJson.
ModelFile ReadModelJsonFor(const std::string& path, const std::string& command);

// InputError when `text` is evidently not JSON but another input of zwidth's
// (HDF5/.mat signature, a text log's or a frequency response's first line),
// naming what it looks like and what takes it; `what` is "model" or "scene".
void CheckNotJsonOfAnotherKind(const std::string& text, const std::string& source, const std::string& what,
                               const std::string& command);
// InputError naming the key and its two lines when an object of `text` (valid
// JSON) repeats a key, which a JSON parser resolves silently (the last wins).
void CheckDuplicateKeys(const std::string& text, const std::string& source);

// The model used at the sample period T (the one rule for a model's delay at
// another period, used by the CLI, the C++ API and Python): its delay_samples
// counts samples of its own sample_period_s T_m, so at T it is d T_m / T when
// that is a whole number (to 1e-9), and the model's period becomes T; a model
// without a period, without a delay or at T already is left as it is. Returns
// a note saying what was converted ("" when nothing was); throws InputError
// saying why and what to do when d T_m / T is not whole or exceeds
// kMaxDelaySamples. `what` names the model in the texts ("the model").
std::string ConvertDelayToPeriod(ModelFile* model, double T, const std::string& what);

// The period a model is used at, the one rule of the CLI's --period, Python's
// period_s and the C++ API (analysis::AnalysePlantStability): `period_s` when
// given, checked like a file's sample_period_s (SamplePeriodProblem), else the
// model's sample_period_s, else 1 ms; the model's delay is then converted to
// it (ConvertDelayToPeriod, whose note is returned in *note, "" when nothing
// was converted). Messages name the argument ModelPeriod::period_s
// (io/option_names.h: --period, period_s).
double ResolveModelPeriod(std::optional<double> period_s, ModelFile* model, std::string* note);

// With "format_version"; WriteModelJson adds the "provenance" (io/provenance.h).
nlohmann::json ModelToJson(const ModelFile& model);
void WriteModelJson(const std::string& path, const ModelFile& model);

}  // namespace zwidth::io
