#include <cmath>
#include <optional>

#include "apps/common.h"
#include "io/atomic_file.h"
#include "io/export.h"
#include "io/frf_file.h"
#include "model/error.h"

namespace zwidth::app {

void AddExportCommand(CLI::App& app) {
  struct Flags { std::string model, out, format = "json", response; double period = kNotGiven; };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("export", "export a model for MATLAB/Octave, Python, HDF5 or as state space");
  cmd->add_option("model", f->model, "model JSON")->required();
  cmd->add_option("--format", f->format, "json | hdf5 | matlab | python | statespace | mat (MATLAB v5) | mat73 (MATLAB v7.3)")->capture_default_str();
  cmd->add_option("--response", f->response, "a measured frequency response (from `zwidth estimate`, or f/H from MATLAB) to store as f, H, H_std, coherence (mat, mat73)");
  cmd->add_option("--period", f->period, "sample period T [s] for the discrete model (default: the model's, if any)");
  cmd->add_option("-o,--output", f->out, "file to write")->required();
  cmd->callback([f] {
    io::CheckOutputFolder(f->out, f->response.empty() ? std::vector<std::string>{f->model} : std::vector<std::string>{f->model, f->response});
    io::ExportFormat fmt;
    if (!io::FromString(f->format, &fmt)) {
      throw InputError("--format '" + f->format + "' is not one of json, hdf5, matlab, python, statespace, mat, mat73");
    }
    io::ModelFile mf = io::ReadModelJsonFor(f->model, "export");  // not const: --period may convert its delay
    double T = 0.0;
    if (!std::isnan(f->period)) T = ResolvePeriod(f->period, &mf);
    else if (mf.sample_period_s) T = *mf.sample_period_s;
    std::optional<ident::FrequencyResponse> response;
    if (!f->response.empty()) response = io::ReadFrequencyResponse(f->response);
    io::ExportModel(mf, fmt, T, f->out, response ? &*response : nullptr);
  });
}

}  // namespace zwidth::app
