#include "io/fit_file.h"

#include <vector>

#include "io/printable.h"
#include "model/error.h"
#include "stability/uncertainty.h"

namespace zwidth::io {
namespace {

nlohmann::json QualityJson(const fit::FitResult& r) {
  nlohmann::json a = nlohmann::json::array();
  for (const fit::QualityReason& q : r.reasons) a.push_back({{"code", q.code}, {"message", q.message}, {"advice", q.advice}});
  return a;
}

nlohmann::json OrderTableJson(const fit::FitResult& r) {
  nlohmann::json a = nlohmann::json::array();
  for (const fit::OrderTrial& t : r.order_table) {
    std::vector<bool> persists(t.persists.begin(), t.persists.end());
    a.push_back({{"modes", t.num_modes}, {"converged", t.converged}, {"chi2_per_dof", t.chi2_per_dof},
                 {"bic", t.bic}, {"pole_hz", t.pole_hz}, {"persists", persists}, {"rejected_because", t.spurious},
                 {"delay_samples", t.delay_samples}});
  }
  return a;
}

}  // namespace

ModelFile FittedModelFile(const fit::FitResult& r, const ident::FrequencyResponse& frf,
                          const fit::FitOptions& o, const std::string& source) {
  ModelFile mf;
  mf.plant = r.plant;
  const std::string shown = Utf8ForJson(source);  // a Latin-1 file name is no valid JSON string
  mf.plant.name = "fitted from " + shown;
  mf.std_errors = r.std_errors;
  mf.log_covariance = r.log_covariance;
  std::string covariance_omitted;
  if (!mf.log_covariance.empty()) {
    try {  // a model file zwidth writes must load: an unusable covariance is left out, and said so
      stability::CheckLogCovariance(mf.plant, mf.log_covariance);
    } catch (const InputError& e) {
      covariance_omitted = e.what();
      mf.log_covariance.clear();
    }
  }
  mf.sample_period_s = frf.period_s();
  mf.fit = {{"status", fit::ToString(r.status)},
            {"source", shown},
            {"quality", fit::ToString(r.quality)},
            {"quality_reasons", QualityJson(r)},
            {"modes", r.plant.modes.size()},
            {"modes_chosen_automatically", o.auto_modes},
            {"order_choice", r.order_choice},
            {"order_table", OrderTableJson(r)},
            {"delay_choice", r.delay_choice},
            {"band", {{"f_min_used_hz", r.band.f_lo_hz}, {"f_max_used_hz", r.band.f_hi_hz},
                      {"num_used", r.band.num_used}, {"num_outside_fmin_fmax", r.band.num_outside},
                      {"num_low_input_power", r.band.num_low_input},
                      {"num_low_coherence", r.band.num_low_coherence},
                      {"min_input_power_ratio", o.band.min_input_power_ratio},
                      {"min_coherence", o.band.min_coherence},
                      {"input_power_checked", r.band.input_power_known}}},
            {"runs_test_z", r.runs_z},
            {"delay_samples", r.plant.delay_samples},
            {"delay_chosen_automatically", o.auto_delay},
            {"chi2_per_dof", r.chi2_per_dof},
            {"nrmse_fit_percent", r.nrmse_fit_percent},
            {"nrmse_note", "100 (1 - |H - G| / |H - mean H|), unweighted: dominated by the largest |H|; judge by chi2/dof and quality"},
            {"worst_misfit_hz", r.worst_misfit_hz},
            {"std_scale", r.std_scale},
            {"covariance_ok", r.covariance_ok && covariance_omitted.empty()},
            {"num_bins", r.num_residuals / 2},
            {"num_averages", frf.num_averages},
            {"estimator", frf.estimator.empty() ? std::string("unknown") : frf.estimator},
            {"sample_rate_hz", frf.sample_rate_hz},
            {"f_min_hz", r.band.f_lo_hz},
            {"f_max_hz", r.band.f_hi_hz},
            {"starts_tried", r.starts_tried},
            {"residual", "exact ZOH response, weighted by the Welch per-bin std"},
            {"order", "canonical: pole pairs sorted by omega, zero pairs by v (G is unchanged)"},
            {"warnings", r.warnings}};
  if (!covariance_omitted.empty()) mf.fit["covariance_omitted"] = covariance_omitted;
  return mf;
}

}  // namespace zwidth::io
