// A fit's result as a model file: the fitted plant, its std and covariance,
// and the fit's metadata ("fit": status, quality verdict and reasons, order
// table, band, chi2/dof, ...) as `zwidth fit` writes it. One writer for the
// CLI and the Python module.
#pragma once

#include <string>

#include "fit/fit.h"
#include "ident/welch.h"
#include "io/model_json.h"

namespace zwidth::io {

// `source` names what was fitted (the plant's name becomes "fitted from <source>").
ModelFile FittedModelFile(const fit::FitResult& r, const ident::FrequencyResponse& frf,
                          const fit::FitOptions& o, const std::string& source);

}  // namespace zwidth::io
