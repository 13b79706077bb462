// zwidth validate MODEL LOG: the model on a log it was not fitted to (MATLAB's
// compare and resid); analysis::Validate computes, this file wires and prints.
#include <cstdio>

#include "analysis/validate.h"
#include "apps/common.h"
#include "io/printable.h"
#include "io/provenance.h"
#include "io/atomic_file.h"
#include "io/model_json.h"
#include "model/error.h"

namespace zwidth::app {
namespace {

struct ValidateFlags {
  std::string model, log, out, trace;
  io::LogSelect select;
  analysis::ValidateOptions options;
};

void Print(const ValidateFlags& f, const io::Log& log, const analysis::ValidationResult& r) {
  std::printf("validate: %s on %s (%zu samples at %g Hz)\n", io::Printable(f.model).c_str(),
              io::Printable(f.log).c_str(), log.input.size(),
              log.info.sample_rate_hz);
  std::printf("  simulation (compare): fit %.4g %% (NRMSE), with the initial state and an input offset of %.4g "
              "estimated\n", r.fit_percent, r.input_offset);
  std::printf("  residual (resid): autocorrelation %d of %zu lags, cross-correlation with the input %d of %zu lags "
              "outside the 99 %% bounds +-%.3g\n", r.autocorrelation_outside, r.residual_autocorrelation.size() - 1,
              r.cross_correlation_outside, r.cross_correlation.size(), r.correlation_bound);
  std::printf("  frequency response: chi2/dof %.4g (limit %.3g) over %s\n", r.chi2_per_dof, r.chi2_limit,
              r.band.Describe().c_str());
  std::printf("quality: %s\n", r.good ? "good" : "poor");
  for (const auto& w : r.reasons) std::printf("  reason: %s\n", w.c_str());
  for (const auto& w : r.warnings) std::printf("  warning: %s\n", io::Printable(w).c_str());
}

}  // namespace

void AddValidateCommand(CLI::App& app) {
  auto f = std::make_shared<ValidateFlags>();
  CLI::App* cmd = app.add_subcommand(
      "validate", "check a model on a log it was not fitted to: simulated output (fit %), residual correlations, "
                  "frequency-response misfit in units of its std, and a verdict");
  cmd->add_option("model", f->model, "model JSON")->required();
  cmd->add_option("log", f->log, "a fresh log of the device (text, HDF5 or .mat)")->required();
  AddLogFlags(cmd, &f->select);
  cmd->add_option("--window-length", f->options.welch.window_length, "samples per Welch segment")->capture_default_str();
  cmd->add_option("--fmin", f->options.band.fmin_hz, "lowest frequency compared [Hz]")->capture_default_str();
  cmd->add_option("--fmax", f->options.band.fmax_hz, "highest frequency compared [Hz]");
  cmd->add_option("--max-lag", f->options.max_lag, "correlation lags [samples]")->capture_default_str();
  cmd->add_option("-o,--output", f->out, "the result as JSON (- for standard output)");
  cmd->add_option("--trace", f->trace, "CSV of t, u, y, y_sim, e per sample");
  cmd->footer("Example: zwidth validate model.json fresh_log.h5 -o validation.json");
  cmd->callback([f] {
    if (!f->out.empty()) io::CheckOutputFolder(f->out, {f->model, f->log});
    if (!f->out.empty()) io::CheckOutputKind(f->out, "the result as JSON", {".json"});
    if (!f->trace.empty()) io::CheckOutputFolder(f->trace, {f->model, f->log});
    if (!f->trace.empty()) io::CheckOutputKind(f->trace, "a trace CSV", io::kCsvExtensions);
    const io::ModelFile mf = io::ReadModelJsonFor(f->model, "validate");
    const io::Log log = io::ReadLog(f->log, f->select);
    const analysis::ValidationResult r = analysis::Validate(mf, log, f->options);
    if (!f->out.empty()) {
      nlohmann::ordered_json j = analysis::ValidationToJson(r);
      j["provenance"] = nlohmann::ordered_json::parse(io::ProvenanceJson().dump());
      io::WriteTextAtomically(f->out, j.dump(2) + "\n");
    }
    if (!f->trace.empty()) io::WriteTextAtomically(f->trace, analysis::ValidationTraceCsv(log, r));
    if (f->out != "-") Print(*f, log, r);
  });
}

}  // namespace zwidth::app
