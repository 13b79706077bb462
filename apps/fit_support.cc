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
  const bool t1 = flag == "table1";
  if (is_table1) *is_table1 = t1;
  return t1 ? io::Table1Model() : io::ReadModelJsonFor(flag, "--reference");
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
                  "leave out regions whose coherence is within this many std of what noise alone gives (e.g. 3, for "
                  "fast logs whose bins near Nyquist are noise; 0: off, the default)")->capture_default_str();
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

namespace {

// A poor fit of a response that eq. (1) cannot have at all: a reversed sign
// (phase near 0 deg where the rigid body gives -90..-180) or the input and
// output swapped (|H| rising with frequency). Read from the response, not the
// fit: the median phase of the lowest tenth of the used bins, and the slope of
// log |H| against log f over all of them, when their median coherence is at
// least 0.5 (a response of quantisation noise has any phase).
std::optional<fit::QualityReason> SignOrSwap(const ident::FrequencyResponse& frf, const fit::FitResult& r) {
  std::vector<size_t> used;
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    const bool in_band = k < r.band.used.size() ? r.band.used[k] != 0 : true;
    if (in_band && frf.f_hz[k] > 0.0 && std::abs(frf.H[k]) > 0.0) used.push_back(k);
  }
  if (used.size() < 8) return std::nullopt;
  // Only a response that is measured at all (not quantisation or noise).
  std::vector<double> coh;
  for (size_t k : used) coh.push_back(frf.coherence[k]);
  std::nth_element(coh.begin(), coh.begin() + coh.size() / 2, coh.end());
  if (!(coh[coh.size() / 2] >= 0.5)) return std::nullopt;
  // Least-squares slope of log10 |H| over log10 f [decades per decade].
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k : used) {
    const double x = std::log10(frf.f_hz[k]), y = std::log10(std::abs(frf.H[k]));
    sx += x; sy += y; sxx += x * x; sxy += x * y;
  }
  const double n = static_cast<double>(used.size());
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const size_t low = std::max<size_t>(4, used.size() / 10);
  std::vector<double> phase;
  for (size_t i = 0; i < low; ++i) phase.push_back(std::arg(frf.H[used[i]]) * 180.0 / std::numbers::pi);
  std::nth_element(phase.begin(), phase.begin() + phase.size() / 2, phase.end());
  const double median_phase = phase[phase.size() / 2];
  auto band_to = [&](size_t last) {  // "f_first-f_last Hz" of the used bins 0..last
    char b[80];
    std::snprintf(b, sizeof b, "%.4g-%.4g Hz", frf.f_hz[used.front()], frf.f_hz[used[last]]);
    return std::string(b);
  };
  const std::string band = band_to(used.size() - 1), low_band = band_to(low - 1);
  char msg[600];
  if (slope > 0.5) {
    std::snprintf(msg, sizeof msg,
                  "|H| rises with frequency (log-log slope %+.2f over %s), while eq. (1) falls (-1 to -2 decades per "
                  "decade): the response looks inverted (1/G)", slope, band.c_str());
    return fit::QualityReason{"columns_swapped", msg,
                              "are the input and output columns swapped? check LogSelect::input_column (the torque "
                              "or force) and LogSelect::output_column (the position)"};
  }
  if (slope < -0.5 && std::abs(median_phase) < 60.0) {
    std::snprintf(msg, sizeof msg,
                  "the response's phase at low frequency is %.0f deg (median over %s), while eq. (1)'s rigid body "
                  "needs -90 to -180 deg there", median_phase, low_band.c_str());
    return fit::QualityReason{"sign_reversed", msg,
                              "is the output's (or the input's) sign reversed, e.g. an encoder counting the other "
                              "way? fit with LogSelect::output_scale -1 (or LogSelect::input_scale -1)"};
  }
  return std::nullopt;
}

}  // namespace

void AddFrictionFlag(CLI::App* cmd, std::string* flag) {
  cmd->add_option("--friction", *flag,
                  "Coulomb friction: auto (fitted when the log shows it), coulomb (always fitted) or none (the linear "
                  "fit; friction only detected); needs one time-domain log")
      ->capture_default_str();
}

fit::FrictionModel ResolveFrictionFlag(const std::string& flag) {
  fit::FrictionModel m;
  if (!fit::FrictionModelFromString(flag, &m)) {
    throw InputError("--friction '" + flag + "': expected none, auto or coulomb");
  }
  return m;
}

std::optional<FrictionInput> FrictionInputFor(const std::vector<std::string>& inputs, bool frf_file,
                                              const EstimateFlags& est, fit::FrictionModel model) {
  if (model == fit::FrictionModel::kNone && (frf_file || inputs.size() != 1)) return std::nullopt;
  if (frf_file || inputs.size() != 1) {
    if (model == fit::FrictionModel::kCoulomb) {
      throw InputError(std::string("--friction coulomb needs one time-domain log, not ") +
                       (frf_file ? "a saved frequency response" : "several logs") +
                       ": fit one log with --friction coulomb, or the runs with --friction none");
    }
    std::fprintf(stderr, "warning: friction not checked (--friction auto needs one time-domain log); the fit is "
                         "linear-only\n");
    return std::nullopt;
  }
  FrictionInput in{inputs[0], est.select, {}};
  in.options.model = model;
  in.options.welch = est.Resolve();
  return in;
}

std::string FrictionLine(const fit::FrictionFitResult& ff) {
  if (ff.status == fit::FrictionFitStatus::kFitted) return "friction: " + ff.message + "\n";
  if (ff.status != fit::FrictionFitStatus::kNotDetected || ff.detected) return "";
  char s[200];
  std::snprintf(s, sizeof s, "friction: none detected (F_c %.3g +- %.2g); the fit is linear\n", ff.detection_coulomb,
                ff.detection_coulomb_std);
  return s;
}

namespace {

// The friction fit's record in model.json's "fit" (the linear-only b beside).
nlohmann::json FrictionRecord(const fit::FrictionFitResult& ff) {
  return {{"status", fit::ToString(ff.status)},
          {"detected", ff.detected},
          {"detection_coulomb", ff.detection_coulomb},
          {"detection_coulomb_std", ff.detection_coulomb_std},
          {"idim_b", ff.idim_b},
          {"idim_b_std", ff.idim_b_std},
          {"linear_only_b", ff.linear_b},
          {"linear_only_b_std", ff.linear_b_std},
          {"cutoff_hz", ff.cutoff_hz},
          {"rows_used", ff.rows_used},
          {"iterations", ff.iterations},
          {"message", ff.message}};
}

}  // namespace

io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, fit::FitResult* out, const FrictionInput* friction,
                             fit::FrictionFitResult* friction_out) {
  // Too few segments at the shortest window: the library's advice (a shorter
  // window) cannot apply; the log is too short.
  constexpr int kShortestWindow = 16;  // WelchOptions::window_length >= 16
  if (frf.num_averages < o.min_averages && !o.allow_few_averages && frf.window_length > 0 &&
      frf.window_length <= kShortestWindow) {  // 0: a saved response, whose window is not known
    throw InputError("the log is too short: " + std::to_string(frf.num_averages) + " Welch segment(s) of " +
                     std::to_string(frf.window_length) + " samples (the shortest window), fewer than the " +
                     std::to_string(o.min_averages) + " a per-bin std needs; record a longer log (at least " +
                     std::to_string((o.min_averages + 1) * frf.window_length / 2) +
                     " samples at 50 % overlap), or FitOptions::allow_few_averages to fit anyway (judged poor)");
  }
  // Ceres' glog output (e.g. "Covariance matrix is near rank deficient") is
  // kept off the terminal; the fit is in a plugin loaded here (fit/fit_api.h).
  fit::FitResult r = fit::FitLibrary().fit_model_quiet(frf, o);
  if (r.quality == fit::FitQuality::kPoor) {  // the likeliest cause first, before "more modes"
    if (auto reason = SignOrSwap(frf, r)) r.reasons.insert(r.reasons.begin(), *reason);
  }
  fit::FrictionFitResult ff;
  // Not on a log whose sign or columns look wrong: its friction would mean nothing.
  const bool broken = !r.reasons.empty() && (r.reasons.front().code == "sign_reversed" ||
                                             r.reasons.front().code == "columns_swapped");
  if (friction && r.status == fit::FitStatus::kConverged && !broken) {
    const io::Log log = io::ReadLog(friction->path, friction->select);
    try {
      ff = fit::FitLibrary().fit_friction_quiet(log.input, log.output, log.info.sample_rate_hz, r, o, friction->options);
    } catch (const InputError& e) {  // e.g. too few usable samples: auto goes on linear-only
      if (friction->options.model == fit::FrictionModel::kCoulomb) throw;
      r.warnings.push_back(std::string("friction not checked: ") + e.what());
    }
    if (ff.status == fit::FrictionFitStatus::kFailed) throw ComputationError(ff.message);
    if (ff.status != fit::FrictionFitStatus::kNotRun) r = ff.fit;
  }
  if (out) *out = r;
  if (friction_out) *friction_out = ff;
  for (const std::string& w : r.warnings) if (!MessagesQuiet()) std::fprintf(stderr, "warning: %s\n", io::Printable(WithFlags(w)).c_str());
  if (r.status != fit::FitStatus::kConverged) throw ComputationError(r.message);
  io::ModelFile mf = io::FittedModelFile(r, frf, o, source);
  if (ff.status == fit::FrictionFitStatus::kFitted) {
    mf.friction = ff.friction;
    mf.friction_std = ff.friction_std;
  }
  if (ff.status != fit::FrictionFitStatus::kNotRun && mf.fit.is_object()) mf.fit["friction"] = FrictionRecord(ff);
  // The files the CLI writes (model JSON, run's summary.json) give its flags:
  // every text of the fit's record (reasons, warnings, order and delay choices).
  std::function<void(nlohmann::json&)> flags = [&](nlohmann::json& j) {
    if (j.is_string()) j = WithFlags(j.get<std::string>());
    else if (j.is_array() || j.is_object()) for (auto& x : j) flags(x);
  };
  flags(mf.fit);
  return mf;
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
