// Model export for other tools: MATLAB/Octave (.m, and .mat v5 or v7.3),
// Python (NumPy + SciPy), HDF5 (layouts in docs/export.md), state-space JSON,
// and the model JSON.
#pragma once

#include <string>
#include <vector>

#include "ident/welch.h"
#include "io/model_json.h"

namespace zwidth::io {

enum class ExportFormat { kJson, kHdf5, kMatlab, kPython, kStateSpace, kMat, kMat73 };
std::string ToString(ExportFormat f);
bool FromString(const std::string& s, ExportFormat* f);

// The extensions of a file in `format` (io::CheckOutputKind): .json (json,
// statespace), .h5/.hdf5/.he5, .m, .py, .mat (mat, mat73).
std::vector<std::string> ExportExtensions(ExportFormat format);

// period_s <= 0: no discrete model (MATLAB/Python define only G). response:
// a measured frequency response to store beside the model (f, H, H_std,
// coherence), .mat formats only (else an InputError); may be null.
void ExportModel(const ModelFile& model, ExportFormat format, double period_s, const std::string& path,
                 const ident::FrequencyResponse* response = nullptr);

}  // namespace zwidth::io
