#include "apps/fit_support.h"
#include "apps/common.h"

#include "analysis/compare.h"
#include "analysis/run.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>

#include "io/reference_models.h"

#include "fit/fit_api.h"
#include "io/fit_file.h"
#include "io/printable.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::app {
io::ModelFile ReadReference(const std::string& flag, bool* is_table1) {
  return io::ReadReferenceModel(flag, "--reference", is_table1);
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
  cmd->add_option("--delay-samples", f->delay, "input delay [samples] or 'auto' (searched from the phase of H / G_rigid)")->capture_default_str();
  cmd->add_option("--max-delay", f->o.max_auto_delay, "largest delay --delay-samples auto tries [samples]")->capture_default_str();
  cmd->add_flag("--allow-short", f->o.allow_few_averages, "fit a response of fewer than 3 Welch segments anyway (judged poor)");
  cmd->add_option("--min-input-power", f->o.band.min_input_power_ratio,
                  "bins used only where the input PSD is at least this fraction of its 99th percentile")->capture_default_str();
  cmd->add_option("--min-coherence", f->o.band.min_coherence, "bins with lower coherence are not used")->capture_default_str();
  cmd->add_option("--noise-coherence-sigmas", f->o.band.noise_coherence_sigmas,
                  "leave out the region at the top of the band whose coherence is within this many std of what "
                  "noise alone gives (bins near Nyquist that are noise; 0: off)")->capture_default_str();
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
    o->auto_delay = false;
  } catch (const std::exception&) {
    throw InputError("--delay-samples '" + flag + "': expected 'auto' or an integer >= 0");
  }
}


void AddFrictionFlag(CLI::App* cmd, std::string* flag) {
  cmd->add_option("--friction", *flag,
                  "Coulomb friction: auto (fitted when the log shows it), coulomb (always fitted) or none (the linear "
                  "fit; friction only detected); needs one time-domain log")
      ->capture_default_str();
}

void AddTable2Flags(CLI::App* cmd, bool* on, analysis::Table2Options* t2) {
  cmd->add_flag("--table2", *on,
                "the paper's measured relay points (Table II) beside the model's linear Z-width and its relay "
                "simulated with Coulomb friction (--coulomb-levels) and an encoder, and the level that explains them "
                "best");
  cmd->add_option("--coulomb-levels", t2->coulomb_levels, "with --table2: the Coulomb levels tried [N m]")
      ->delimiter(',')->capture_default_str();
  cmd->add_option("--encoder-step", t2->encoder_step, "with --table2: the relay's encoder step [rad per count]")
      ->capture_default_str();
  cmd->add_option("--amplitude", t2->relay_amplitude, "with --table2: the relay amplitude [N m]")->capture_default_str();
  cmd->add_option("--seconds", t2->seconds, "with --table2: each relay run's length [s]")->capture_default_str();
}

std::string FrictionLine(const fit::FrictionFitResult& ff) {
  if (ff.status == fit::FrictionFitStatus::kFitted) return "friction: " + ff.message + "\n";
  if (ff.status == fit::FrictionFitStatus::kNotIdentified) return "friction: not identified; the fit is linear (see the warning)\n";
  if (ff.status != fit::FrictionFitStatus::kNotDetected || ff.detected) return "";
  char s[200];
  std::snprintf(s, sizeof s, "friction: none detected (F_c %.3g +- %.2g); the fit is linear\n", ff.detection_coulomb,
                ff.detection_coulomb_std);
  return s;
}


io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, bool linear, fit::FitResult* out, const FrictionInput* friction,
                             fit::FrictionFitResult* friction_out) {
  analysis::FitMessages messages{.words = WithFlags, .warning = [](const std::string& w) {
    std::fprintf(stderr, "warning: %s\n", io::Printable(WithFlags(w)).c_str());
  }, .linear = linear};
  return analysis::FitToModelFile(frf, o, source, messages, out, friction, friction_out);
}

std::string ParameterTable(const io::ModelFile& mf, bool linear) { return analysis::ParameterTable(mf, linear); }

nlohmann::json CompareModels(const io::ModelFile& model, const io::ModelFile& ref,
                             const std::vector<int>& delays, double T, std::string* text, bool linear) {
  analysis::ModelComparison c = analysis::CompareModels(model, ref, delays, analysis::SummarizeDelays(model, T, delays),
                                                        analysis::ReferenceStabilityOf(ref, T, delays).summaries, linear);
  if (text) *text = std::move(c.text);
  return std::move(c.json);
}

}  // namespace zwidth::app
