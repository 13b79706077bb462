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








// The relay's options mean nothing without --table2: given alone they were
// silently ignored (even --amplitude -1), so each needs it (CLI11 names both).
void AddTable2Flags(CLI::App* cmd, bool* on, analysis::Table2Options* t2) {
  CLI::Option* table2 = cmd->add_flag("--table2", *on,
                "the paper's measured relay points (Table II) beside the model's linear Z-width and its relay "
                "simulated with Coulomb friction (--coulomb-levels) and an encoder, and the level that explains them "
                "best");
  cmd->add_option("--coulomb-levels", t2->coulomb_levels, "with --table2: the Coulomb levels tried [N m]")
      ->delimiter(',')->capture_default_str()->needs(table2);
  cmd->add_option("--encoder-step", t2->encoder_step, "with --table2: the relay's encoder step [rad per count]")
      ->capture_default_str()->needs(table2);
  cmd->add_option("--amplitude", t2->relay_amplitude, "with --table2: the relay amplitude [N m]")->capture_default_str()->needs(table2);
  cmd->add_option("--seconds", t2->seconds, "with --table2: each relay run's length [s]")->capture_default_str()->needs(table2);
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
