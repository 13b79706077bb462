// A design file for `zwidth batch --reference DESIGN.json` (issue 28): the
// design's model and the tolerances a unit must meet, per parameter (m, b,
// mode<i>_{omega,c,v,d}) and per Z-width figure at a delay (K_cr_at_zero_B,
// K_cr_max, B_t, B_max, B_max_from_zero). The schema:
// docs/schema/design.schema.json; an example in docs/fleet.md.
//
//   {"format": "zwidth-design", "format_version": 1, "name": "PHANToM axis 1",
//    "model": "table1" | "model.json" (from the design file's folder) | {a model JSON object},
//    "tolerances": [
//      {"parameter": "m", "relative": 0.15},              // |m - m_design| <= 15 % of m_design
//      {"parameter": "b", "min": 1e-3, "max": 0.02},      // absolute bounds
//      {"parameter": "mode1_omega", "absolute": 40},      // |omega - omega_design| <= 40 rad/s
//      {"figure": "K_cr_max", "delay": 2, "min": 1.2},    // K_CR^max >= 1.2 at delay 2
//      {"figure": "B_t", "delay": 4, "relative": 0.3}]}   // within 30 % of the design's B_t
//
// Each tolerance has "parameter" or "figure" (then "delay"), and either
// "min" and/or "max", or "relative" (> 0), or "absolute" (> 0); a relative or
// absolute one is around the design's value (a figure's: the design model's
// Z-width at that delay on the run's loop). Any other key is an error.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/model_json.h"

namespace zwidth::io {

struct DesignTolerance {
  std::string column;                 // the table's column: "m", "mode1_omega", "d2_K_cr_max"
  bool is_figure = false;             // a Z-width figure (then delay) or a parameter
  int delay = 0;                      // [samples], figures only
  std::string figure;                 // K_cr_at_zero_B, K_cr_max, B_t, B_max, B_max_from_zero (figures)
  std::optional<double> min, max;     // absolute bounds, in the column's SI unit
  std::optional<double> relative;     // fraction of the design's value, > 0
  std::optional<double> absolute;     // +- around the design's value, > 0
  std::string where;                  // "design.json line 12, tolerances[2]", for messages
};

struct Design {
  std::string name;                   // "" when absent
  ModelFile model;                    // the design's model
  std::string model_name;             // "table1", the model file's path, or "<design> key 'model'"
  bool model_is_table1 = false;
  std::vector<DesignTolerance> tolerances;  // at least one
};

// True when `path` is a JSON file whose top level has "format": "zwidth-design"
// (so --reference takes it as a design rather than a model); false for
// anything else (a model JSON, table1, an unreadable file: the model reader
// then says what is wrong).
bool IsDesignFile(const std::string& path);

// Parses and validates; InputError naming the file, the line and the key,
// and what to write instead. `folder` resolves a relative "model" path.
Design ParseDesign(const std::string& text, const std::string& source, const std::string& folder);
Design ReadDesign(const std::string& path);

}  // namespace zwidth::io
