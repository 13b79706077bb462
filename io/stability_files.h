// Files of the stability commands: the boundary CSV, the summary JSON, and
// haptic scenes {"objects": [{"name": "wall", "K": 20.0, "B": 0.05}, ...]}.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "stability/zwidth.h"

namespace zwidth::io {

struct BoundaryRow {
  int delay_samples = 0;
  stability::CriticalPoint point;
};

// Columns: delay_samples,B,K_cr,f_cr_hz,K_margin,f_margin_hz,
// unstable_at_zero_k,margin_agrees,verified. inf and nan are written as such.
void WriteBoundaryCsv(const std::string& path, const std::vector<BoundaryRow>& rows);

// NaN and inf become null.
nlohmann::json SummaryToJson(const stability::DelaySummary& s);
nlohmann::json NumberOrNull(double v);

struct SceneObject {
  std::string name;
  double K = 0.0;  // N m/rad, >= 0
  double B = 0.0;  // N m s/rad, >= 0
};
std::vector<SceneObject> ReadScene(const std::string& path);

}  // namespace zwidth::io
