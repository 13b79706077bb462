#include "io/option_names.h"

#include <algorithm>
#include <cctype>

namespace zwidth::io {

const std::vector<OptionName>& OptionNames() {
  static const std::vector<OptionName> table = {
      {"LogSelect::time_column", "--time-column", "time_column"},
      {"LogSelect::input_column", "--input-column", "input_column"},
      {"LogSelect::output_column", "--output-column", "output_column"},
      {"LogSelect::delimiter", "--delimiter", "delimiter"},
      {"LogSelect::input_scale", "--input-scale", "input_scale"},
      {"LogSelect::output_scale", "--output-scale", "output_scale"},
      {"LogSelect::time_unit", "--time-unit", "time_unit"},
      {"LogSelect::time_dataset", "--time-dataset", "time_dataset"},
      {"LogSelect::input_dataset", "--input-dataset", "input_dataset"},
      {"LogSelect::output_dataset", "--output-dataset", "output_dataset"},
      {"LogSelect::sample_rate_hz", "--rate", "rate"},
      {"ReadFrequencyResponse::sample_rate_hz", "--rate", "sample_rate_hz"},
      {"OutputFolder::force", "--force", "force"},
      {"WelchOptions::window_length", "--window-length", "window_length"},
      {"WelchOptions::detrend", "--detrend", "detrend"},
      {"WelchOptions::window", "--window", "window"},
      {"WelchOptions::estimator", "--estimator", "estimator"},
      {"BatchOptions::threads", "--jobs", ""},
      {"BatchOptions::specs", "--spec", ""},
      {"PopulationOptions::outlier_quantile", "--outlier-quantile", ""},
      {"PopulationOptions::reason_z", "", ""},
      {"PopulationOptions::min_units", "", ""},
      {"HistogramOptions::bins", "", ""},
      {"HistogramOptions::mad_multiple", "", ""},
      {"HistogramOptions::tail", "", ""},
      {"LogsEstimateOptions::whole_record", "--whole-record", "whole_record"},
      {"LogsEstimateOptions::period_samples", "--period-samples", "period_samples"},
      {"LogsEstimateOptions::reference_column", "--reference-column", "reference_column"},
      {"LogsEstimateOptions::reference_dataset", "--reference-dataset", "reference_dataset"},
      {"WelchOptions::overlap", "--overlap", "overlap"},
      {"WelchOptions::fmin_hz", "--fmin", "fmin"},
      {"WelchOptions::fmax_hz", "--fmax", "fmax"},
      {"BandOptions::fmin_hz", "--fmin", "fmin"},
      {"BandOptions::fmax_hz", "--fmax", "fmax"},
      {"BandOptions::min_input_power_ratio", "--min-input-power", "min_input_power_ratio"},
      {"BandOptions::min_coherence", "--min-coherence", "min_coherence"},
      {"ExcitationOptions::sample_rate_hz", "--rate", ""},
      {"ExcitationOptions::seconds", "--seconds", ""},
      {"ExcitationOptions::rms", "--rms", ""},
      {"ExcitationOptions::fmin_hz", "--fmin", ""},
      {"ExcitationOptions::fmax_hz", "--fmax", ""},
      {"SimulateOptions::seconds", "--seconds", "seconds"},
      {"SimulateOptions::sample_rate_hz", "--rate", "sample_rate_hz"},
      {"SimulateOptions::torque_rms", "--torque-rms", "torque_rms"},
      {"SimulateOptions::bandwidth_hz", "--bandwidth-hz", "bandwidth_hz"},
      {"SimulateOptions::encoder_step_rad", "--encoder-step", "encoder_step_rad"},
      {"SimulateOptions::noise_std_rad", "--noise-std", "noise_std_rad"},
      {"SimulateOptions::delay_samples", "--delay-samples", "delay_samples"},
      {"FitOptions::num_modes", "--modes", "modes"},
      {"FitOptions::auto_modes", "--modes auto", "modes='auto'"},
      {"FitOptions::max_modes", "--max-modes", "max_modes"},
      {"FitOptions::delay_samples", "--delay-samples", "delay_samples"},
      {"FitOptions::auto_delay", "--delay-samples auto", "delay_samples='auto'"},
      {"FitOptions::max_auto_delay", "--max-delay", "max_auto_delay"},
      {"FitOptions::allow_few_averages", "--allow-short", "allow_short=True"},
      {"FitOptions::max_iterations", "--max-iterations", "max_iterations"},
      {"FitOptions::max_starts", "--starts", "max_starts"},
      {"FitOptions::init", "--init", "init"},
      {"FitOptions::min_averages", "", ""},
      {"FitOptions::min_damping_ratio", "", "min_damping_ratio"},
      {"FitOptions::max_pole_damping_ratio", "", "max_pole_damping_ratio"},
      {"FitOptions::max_zero_damping_ratio", "", "max_zero_damping_ratio"},
      {"FitOptions::max_frequency_fraction", "", "max_frequency_fraction"},
      {"FitOptions::relative_std_floor", "", "relative_std_floor"},
      {"FitOptions::function_tolerance", "", "function_tolerance"},
      {"FitOptions::max_converged_starts", "", ""},
      {"FitOptions::runner_up_cost_ratio", "", ""},
      {"BGridOptions::b_min", "--b-min", ""},
      {"BGridOptions::b_max", "--b-max", ""},
      {"CutoffSweepOptions::area_B_max", "--area-b-max", ""},
      {"BGridOptions::b_step", "--b-step", "b_step"},
      {"BGridOptions::b_points", "--b-points", "b_points"},
      {"SummaryMonteCarlo::samples", "--monte-carlo", "monte_carlo"},
      {"PlantStabilityOptions::delays", "--delays", "delays"},
      {"PlantStabilityOptions::loops", "--hand", "hand"},
      {"PlantStabilityOptions::monte_carlo", "--monte-carlo", "monte_carlo"},
      {"SetLowPassFilter::cutoff_hz", "--velocity-filter-hz", "velocity_filter_hz"},
      {"LoopOptions::hand", "--hand", "hand"},
      {"RunOptions::delays", "--delays", "delays"},
      {"RunOptions::report_filter_hz", "--report-filter-hz", "report_filter_hz"},
      {"RelayOptions::period_s", "--period", "period_s"},
      {"ModelPeriod::period_s", "--period", "period_s"},
      {"RelayOptions::delay_samples", "--delay", "delay_samples"},
      {"RelayOptions::damping", "--damping", "damping"},
      {"RelayOptions::amplitude", "--amplitude", "amplitude"},
      {"RelayOptions::seconds", "--seconds", "seconds"},
      {"RelayOptions::settle_fraction", "", "settle_fraction"},
      {"RelayOptions::loop", "", ""},
      {"BoundaryOptions::min_grid_points", "", "min_grid_points"},
      {"BoundaryOptions::grid_points_per_delay", "", "grid_points_per_delay"},
      {"BoundaryOptions::theta_tolerance", "", "theta_tolerance"},
      {"PassivityOptions::min_grid_points", "", ""},
      {"PassivityOptions::grid_points_per_delay", "", ""},
      {"PassivityOptions::theta_tolerance", "", ""},
      {"UncertaintyOptions::log_step", "", ""},
      {"ValidateOptions::max_lag", "--max-lag", ""},
      {"ValidateOptions::min_averages", "", ""},
      {"ValidateOptions::relative_std_floor", "", ""},
      {"LocalModelOptions::method", "--estimator", "estimator"},
      {"LocalModelOptions::half_width", "--local-half-width", "local_half_width"},
      {"LocalModelOptions::order", "--local-order", "local_order"},
      {"LocalModelOptions::denominator_order", "--local-denominator-order", "local_denominator_order"},
      {"LocalModelOptions::differences", "--local-differences", "local_differences"},
      {"LocalModelOptions::fmin_hz", "--fmin", "fmin"},
      {"LocalModelOptions::fmax_hz", "--fmax", "fmax"},
      {"RobustOptions::period_samples", "--period-samples", "period_samples"},
      {"RobustOptions::transient_periods", "--transient-periods", "transient_periods"},
      {"RobustOptions::fmin_hz", "--fmin", "fmin"},
      {"RobustOptions::fmax_hz", "--fmax", "fmax"},
      {"FrictionFitOptions::model", "--friction", "friction"},
      {"ModelFile::linear", "--units", "units"},
      {"Table2Options::coulomb_levels", "--coulomb-levels", ""},
      {"Table2Options::encoder_step", "--encoder-step", ""},
      {"Table2Options::relay_amplitude", "--amplitude", ""},
      {"Table2Options::seconds", "--seconds", ""},
      {"FrictionFitOptions::cutoff_hz", "", ""},
      {"FrictionFitOptions::min_speed_fraction", "", ""},
      {"FrictionFitOptions::iterations", "", ""},
      {"FrictionFitOptions::detection_z", "", ""},
      {"FitOptions::local_relative_std_floor", "", ""},
      {"LogSelect::input_unit", "--input-unit", ""},
      {"LogSelect::output_unit", "--output-unit", ""},
      {"LogSelect::counts_per_rev", "--counts-per-rev", ""},
      {"LogSelect::counts_per_m", "--counts-per-m", ""},
      {"LogSelect::decimal_comma", "--decimal-comma", ""},
      {"RelayOptions::encoder_step", "--encoder-step", ""},
      {"RelayOptions::friction", "", ""},
      {"RelayOptions::actuator", "", ""},
      {"WallOptions::friction", "", ""},
      {"WallOptions::actuator", "", ""},
      {"WallOptions::loop", "", ""},
      {"FrictionPredictionOptions::relative_tolerance", "", ""},
      {"FrictionPredictionOptions::max_extra_damping_factor", "", ""},
      {"FrictionAmplitudeOptions::k_factor", "--amplitude-k-factor", ""},
      {"FrictionAmplitudeOptions::encoder_step", "--encoder-step", ""},
      {"FrictionAmplitudeOptions::prediction", "", ""},
      {"FrictionAmplitudeOptions::rows_per_delay", "", ""},
      {"WallOptions::period_s", "--period", ""},
      {"WallOptions::delay_samples", "--delay", ""},
      {"WallOptions::stiffness", "--stiffness", ""},
      {"WallOptions::damping", "--damping", ""},
      {"WallOptions::seconds", "--seconds", ""},
      {"WallOptions::initial_position", "--initial-position", ""},
      {"WallOptions::encoder_step", "--encoder-step", ""},
  };
  return table;
}

namespace {

// The message with each Name::name it holds replaced by name_of(row) of its
// row (left as it is without a row or when that column is "").
template <typename Column>
std::string Replaced(const std::string& message, Column name_of) {
  std::string out;
  size_t i = 0;
  while (i < message.size()) {
    // A field is Name::name: an upper-case identifier, "::", a lower-case one.
    const size_t colon = message.find("::", i);
    if (colon == std::string::npos) break;
    size_t b = colon;
    while (b > i && (std::isalnum(static_cast<unsigned char>(message[b - 1])) || message[b - 1] == '_')) --b;
    size_t e = colon + 2;
    while (e < message.size() && (std::isalnum(static_cast<unsigned char>(message[e])) || message[e] == '_')) ++e;
    const std::string field = message.substr(b, e - b);
    const char* name = nullptr;
    for (const OptionName& row : OptionNames()) {
      if (field == row.field && *name_of(row)) name = name_of(row);
    }
    out += message.substr(i, b - i);
    out += name ? std::string(name) : field;
    i = e;
  }
  return out + message.substr(std::min(i, message.size()));
}

}  // namespace

std::string WithFlags(const std::string& message) {
  return Replaced(message, [](const OptionName& r) { return r.flag; });
}

std::string WithKeywords(const std::string& message) {
  return Replaced(message, [](const OptionName& r) { return r.keyword; });
}

}  // namespace zwidth::io
