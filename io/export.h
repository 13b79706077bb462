// Model export for other tools: MATLAB/Octave (.m), Python (NumPy + SciPy),
// HDF5 (layout in docs/export.md), state-space JSON, and the model JSON.
#pragma once

#include <string>

#include "io/model_json.h"

namespace zwidth::io {

enum class ExportFormat { kJson, kHdf5, kMatlab, kPython, kStateSpace };
std::string ToString(ExportFormat f);
bool FromString(const std::string& s, ExportFormat* f);

// period_s <= 0: no discrete model (MATLAB/Python define only G).
void ExportModel(const ModelFile& model, ExportFormat format, double period_s, const std::string& path);

}  // namespace zwidth::io
