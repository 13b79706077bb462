// Reference data built into the library, so that an installed zwidth needs no
// source tree: Table I of Gil et al. (the PHANToM 1.0 phi-axis model) and
// Table II (the relay experiment's measured K_CR and f_CR per delay and B).
#pragma once

#include <string>
#include <vector>

#include "io/model_json.h"

namespace zwidth::io {

// Table I as a model file (parsed from the embedded datasets/phantom/table1.json).
ModelFile Table1Model();

// A run's reference model: "table1" (Table I, built in; *is_table1 set) or a
// model JSON's path, read with io::ReadModelJsonFor(spec, what) (`what`: the
// option that named it, in the caller's words: "--reference", "reference").
ModelFile ReadReferenceModel(const std::string& spec, const std::string& what, bool* is_table1 = nullptr);

struct Table2Point {
  int delay_samples = 0;
  double B = 0.0;        // N m s/rad
  double K_cr = 0.0;     // N m/rad
  double f_cr_hz = 0.0;  // Hz
};
// Table II (embedded datasets/phantom/table2.csv).
std::vector<Table2Point> Table2Points();

}  // namespace zwidth::io
