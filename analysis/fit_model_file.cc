#include "analysis/fit_model_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit/fit_api.h"
#include "ident/encoder_step.h"
#include "io/fit_file.h"
#include "model/error.h"

namespace zwidth::analysis {
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


// The friction fit's record in model.json's "fit" (the linear-only b beside).
nlohmann::json FrictionRecord(const fit::FrictionFitResult& ff) {
  nlohmann::json j = {{"status", fit::ToString(ff.status)},
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
  if (ff.status == fit::FrictionFitStatus::kFitted) {
    // Where the friction acts, chosen by the first round's IDIM residual (fit/friction_fit.h).
    j["topology"] = fit::ToString(ff.topology);
    j["rigid_body_residual_rms"] = ff.rigid_body_residual_rms;
    j["collocated_residual_rms"] = ff.collocated_residual_rms;
  }
  return j;
}

}  // namespace

fit::FrictionModel FrictionModelNamed(const std::string& word) {
  fit::FrictionModel m;
  if (!fit::FrictionModelFromString(word, &m)) {
    throw InputError("FrictionFitOptions::model '" + word.substr(0, 40) + "': expected none, auto or coulomb");
  }
  return m;
}

std::optional<FrictionInput> FrictionInputFor(const std::vector<std::string>& logs, bool frf_file,
                                              const io::LogSelect& select, const ident::WelchOptions& welch,
                                              fit::FrictionModel model, std::string* warning) {
  if (frf_file || logs.size() != 1) {
    if (model == fit::FrictionModel::kCoulomb) {
      throw InputError(std::string("FrictionFitOptions::model coulomb needs one time-domain log, not ") +
                       (frf_file ? "a saved frequency response" : std::to_string(logs.size()) + " logs") +
                       ": fit one log with FrictionFitOptions::model coulomb, or the runs with "
                       "FrictionFitOptions::model none");
    }
    if (model == fit::FrictionModel::kAuto && warning) {
      *warning = "friction not checked (FrictionFitOptions::model auto needs one time-domain log); the fit is "
                 "linear-only";
    }
    return std::nullopt;
  }
  FrictionInput in{logs[0], select, {}, std::nullopt};
  in.options.model = model;
  in.options.welch = welch;
  return in;
}

FrictionInput FrictionInputFor(io::Log log, const ident::WelchOptions& welch, fit::FrictionModel model) {
  FrictionInput in{log.info.source, {}, {}, std::move(log)};
  in.options.model = model;
  in.options.welch = welch;
  return in;
}

io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, const FitMessages& messages, fit::FitResult* out,
                             const FrictionInput* friction, fit::FrictionFitResult* friction_out) {
  // Ceres' glog output (e.g. "Covariance matrix is near rank deficient") is
  // kept off the terminal; the fit is in a plugin loaded here (fit/fit_api.h).
  fit::FitResult r = fit::FitLibrary().fit_model_quiet(frf, o);
  if (r.quality == fit::FitQuality::kPoor) {  // the likeliest cause first, before "more modes"
    if (auto reason = SignOrSwap(frf, r)) r.reasons.insert(r.reasons.begin(), *reason);
  }
  fit::FrictionFitResult ff;
  double encoder_step = 0.0;  // of the friction fit's log (ident::EncoderStep), 0: not known
  // Not on a log whose sign or columns look wrong: its friction would mean nothing.
  const bool broken = !r.reasons.empty() && (r.reasons.front().code == "sign_reversed" ||
                                             r.reasons.front().code == "columns_swapped");
  if (friction && r.status == fit::FitStatus::kConverged && !broken) {
    std::optional<io::Log> read;
    if (!friction->log) read = io::ReadLog(friction->path, friction->select);
    const io::Log& log = friction->log ? *friction->log : *read;
    encoder_step = ident::EncoderStep(log.output);
    fit::FrictionFitOptions fo = friction->options;
    if (fo.welch.window_length == 0) fo.welch.window_length = frf.window_length;  // the linear fit's estimate
    fo.linear = messages.linear;
    try {
      ff = fit::FitLibrary().fit_friction_quiet(log.input, log.output, log.info.sample_rate_hz, r, o, fo);
    } catch (const InputError& e) {  // e.g. too few usable samples: auto goes on linear-only
      if (friction->options.model == fit::FrictionModel::kCoulomb) throw;
      r.warnings.push_back(std::string("friction not checked: ") + e.what());
    }
    // kNotIdentified: ff.fit is the linear fit, its warning says why (no error: the linear model stands).
    if (ff.status != fit::FrictionFitStatus::kNotRun) r = ff.fit;
  }
  if (out) *out = r;
  if (friction_out) *friction_out = ff;
  if (messages.warning) for (const std::string& w : r.warnings) messages.warning(w);
  if (r.status != fit::FitStatus::kConverged) throw ComputationError(r.message);
  io::ModelFile mf = io::FittedModelFile(r, frf, o, source);
  mf.linear = messages.linear;
  // Only a step the model file can hold (a log in raw counts, q = 1, is; q > 1 rad per count is a unit slip).
  if (encoder_step >= io::kPlausibleMin && encoder_step <= io::kMaxEncoderStep) mf.encoder_step = encoder_step;
  if (ff.status == fit::FrictionFitStatus::kFitted) {
    mf.friction = ff.friction;
    mf.friction_std = ff.friction_std;
  }
  if (ff.status != fit::FrictionFitStatus::kNotRun && mf.fit.is_object()) mf.fit["friction"] = FrictionRecord(ff);
  // The files written (model JSON, run's summary.json) give the caller's words:
  // every text of the fit's record (reasons, warnings, order and delay choices).
  std::function<void(nlohmann::json&)> words = [&](nlohmann::json& j) {
    if (j.is_string()) j = messages.Words(j.get<std::string>());
    else if (j.is_array() || j.is_object()) for (auto& x : j) words(x);
  };
  if (messages.words) words(mf.fit);
  return mf;
}

}  // namespace zwidth::analysis
