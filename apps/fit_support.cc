#include "apps/fit_support.h"
#include "apps/common.h"

#include "analysis/compare.h"
#include "analysis/run.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "io/reference_models.h"

#include "fit/fit_api.h"
#include "io/fit_file.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::app {
io::ModelFile ReadReference(const std::string& flag, bool* is_table1) {
  const bool t1 = flag == "table1";
  if (is_table1) *is_table1 = t1;
  return t1 ? io::Table1Model() : io::ReadModelJson(flag);
}

void ResolveModesFlag(const std::string& flag, fit::FitOptions* o) {
  if (flag == "auto") { o->auto_modes = true; return; }
  try {
    size_t pos = 0;
    const int n = std::stoi(flag, &pos);
    if (pos != flag.size() || n < 0) throw std::invalid_argument("");
    o->num_modes = n;
    o->auto_modes = false;
  } catch (const std::exception&) {
    throw InputError("--modes '" + flag + "': expected 'auto' or an integer >= 0");
  }
}

void AddFitFlags(CLI::App* cmd, FitFlags* f) {
  cmd->add_option("--modes", f->modes, "resonance/antiresonance sections (0: rigid body) or 'auto' (0..--max-modes, by BIC)")->capture_default_str();
  cmd->add_option("--max-modes", f->o.max_modes, "largest order --modes auto tries, <= 8")->capture_default_str();
  cmd->add_option("--delay-samples", f->delay, "input delay [samples] or 'auto' (searched around the phase slope's)")->capture_default_str();
  cmd->add_option("--max-delay", f->o.max_auto_delay, "largest delay --delay-samples auto tries [samples]")->capture_default_str();
  cmd->add_flag("--allow-short", f->o.allow_few_averages, "fit a response of fewer than 3 Welch segments anyway (judged poor)");
  cmd->add_option("--min-input-power", f->o.band.min_input_power_ratio,
                  "bins used only where the input PSD is at least this fraction of its 99th percentile")->capture_default_str();
  cmd->add_option("--min-coherence", f->o.band.min_coherence, "bins with lower coherence are not used")->capture_default_str();
}

void FitFlags::Resolve(double fmin_hz, double fmax_hz) {
  ResolveModesFlag(modes, &o);
  ResolveDelayFlag(delay, &o);
  o.band.fmin_hz = fmin_hz;
  o.band.fmax_hz = fmax_hz;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
}

// The library names option fields; the CLI shows its flags (WithFlags).
std::string FitReport(const fit::FitResult& r) { return WithFlags(analysis::FitReport(r)); }

void ResolveDelayFlag(const std::string& flag, fit::FitOptions* o) {
  if (flag == "auto") { o->auto_delay = true; return; }
  try {
    size_t pos = 0;
    const int d = std::stoi(flag, &pos);
    if (pos != flag.size() || d < 0) throw std::invalid_argument("");
    o->delay_samples = d;
  } catch (const std::exception&) {
    throw InputError("--delay-samples '" + flag + "': expected 'auto' or an integer >= 0");
  }
}

io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, fit::FitResult* out) {
  // Ceres' glog output (e.g. "Covariance matrix is near rank deficient") is
  // kept off the terminal; the fit is in a plugin loaded here (fit/fit_api.h).
  const fit::FitResult r = fit::FitLibrary().fit_model_quiet(frf, o);
  if (out) *out = r;
  for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s\n", WithFlags(w).c_str());
  if (r.status != fit::FitStatus::kConverged) throw ComputationError(r.message);
  io::ModelFile mf = io::FittedModelFile(r, frf, o, source);
  // The files the CLI writes (model JSON, run's summary.json) give its flags.
  for (auto& q : mf.fit["quality_reasons"]) {
    for (const char* k : {"message", "advice"}) q[k] = WithFlags(q[k].get<std::string>());
  }
  return mf;
}

std::string ParameterTable(const io::ModelFile& mf, bool linear) { return analysis::ParameterTable(mf, linear); }

nlohmann::json CompareModels(const io::ModelFile& model, const io::ModelFile& ref,
                             const std::vector<int>& delays, double T, std::string* text, bool linear) {
  const stability::SampledPlant sr(ref.plant, T);
  std::vector<stability::DelaySummary> rs;
  for (int d : delays) rs.push_back(stability::ZWidth(sr, d).Summarize());
  analysis::ModelComparison c =
      analysis::CompareModels(model, ref, delays, analysis::SummarizeDelays(model, T, delays), rs, linear);
  if (text) *text = std::move(c.text);
  return std::move(c.json);
}

}  // namespace zwidth::app
