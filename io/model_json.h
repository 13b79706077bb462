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
//    "fit": {...}}                                    // fit metrics, free form
// Any other key is an error, so that a typo cannot pass silently.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/plant.h"

namespace zwidth::io {

struct ModelFile {
  Plant plant;
  // Standard errors, same shape as plant (fields may be +inf = unknown).
  std::optional<Plant> std_errors;
  std::optional<double> sample_period_s;
  // (2 + 4 N)^2 row-major covariance of the log parameters; empty = none.
  std::vector<double> log_covariance;
  nlohmann::json fit;  // null when absent
};

// Parses and validates; throws InputError naming the file and the key.
ModelFile ParseModelJson(const std::string& text, const std::string& source);
ModelFile ReadModelJson(const std::string& path);

nlohmann::json ModelToJson(const ModelFile& model);
void WriteModelJson(const std::string& path, const ModelFile& model);

}  // namespace zwidth::io
