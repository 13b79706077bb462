#include "flags/estimate_flags.h"

#include "flags/flag_guard.h"

#include "io/model_json.h"
#include "io/option_names.h"
#include "model/error.h"

namespace zwidth::flags {

std::string EstimateFlags::ResolvedDetrend() const {
  if (!detrend.empty()) return detrend;
  return ident::ToString(analysis::DefaultDetrend(whole_record));
}

ident::WelchOptions EstimateFlags::Resolve() const {
  return ident::ParseWelchOptions(welch, window, ResolvedDetrend(), estimator);  // InputError in fields
}

ident::LocalModelOptions EstimateFlags::ResolveLocal() const {
  ident::LocalModelOptions o = local;
  ident::FromString(estimator, &o.method);
  o.fmin_hz = welch.fmin_hz;
  o.fmax_hz = welch.fmax_hz;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(io::WithFlags(why));
  return o;
}

void AddLogFlags(CLI::App* cmd, io::LogSelect* s) {
  cmd->add_option("--input-column", s->input_column, "input column: header name or 1-based position (text), variable (.mat)")->capture_default_str();
  cmd->add_option("--output-column", s->output_column, "output column: name or position (text), variable (.mat)")->capture_default_str();
  cmd->add_option("--time-column", s->time_column, "time column: name or position (text), variable (.mat); 'none' with --rate")->capture_default_str();
  cmd->add_option("--delimiter", s->delimiter, "text field separator: , ; tab space (default: detected)");
  cmd->add_option("--input-scale", s->input_scale, "factor applied to the input (e.g. volts -> N m)")->capture_default_str();
  cmd->add_option("--output-scale", s->output_scale, "factor applied to the output (e.g. counts -> rad)")->capture_default_str();
  cmd->add_option("--time-unit", s->time_unit, "unit of the text time column: s | ms | us (default s)");
  cmd->add_option("--input-unit", s->input_unit, "unit of the text input column (mN m, N mm, N, ...; si: as is; default: from the header, else N m)");
  cmd->add_option("--output-unit", s->output_unit, "unit of the text output column (deg, rad, mm, um, m, counts, ...; si: as is; default: from the header, else rad)");
  cmd->add_option("--counts-per-rev", s->counts_per_rev, "encoder counts per turn, for an output in counts (to rad)")
      ->check(NonZeroWhenGiven());
  cmd->add_option("--counts-per-m", s->counts_per_m, "encoder counts per metre, for an output in counts (to m)")
      ->check(NonZeroWhenGiven());
  cmd->add_flag("--decimal-comma", s->decimal_comma, "text numbers use ',' as the decimal mark (detected when the first data line reads only so)");
  cmd->add_option("--input-dataset", s->input_dataset, "HDF5 dataset of the input")->capture_default_str();
  cmd->add_option("--output-dataset", s->output_dataset, "HDF5 dataset of the output")->capture_default_str();
  cmd->add_option("--time-dataset", s->time_dataset, "HDF5 dataset of the time stamps")->capture_default_str();
  cmd->add_option("--rate", s->sample_rate_hz, "sample rate [Hz], overrides the log's (time column then only checked to increase)")
      ->check(NonZeroWhenGiven());
}

void AddEstimateFlags(CLI::App* cmd, EstimateFlags* f) {
  AddLogFlags(cmd, &f->select);
  cmd->add_option("--window", f->window, "hann | hamming | rect (periodic)")->capture_default_str();
  cmd->add_option("--window-length", f->welch.window_length,
                  "samples per Welch segment (default: the power of two nearest 4.096 s at the log's rate, halved until "
                  "the log holds 3 segments: 4096 at 1 kHz, 16384 at 5 kHz)")
      ->check(NonZeroWhenGiven());
  cmd->add_option("--overlap", f->welch.overlap, "segment overlap fraction in [0, 1)")->capture_default_str();
  cmd->add_option("--detrend", f->detrend,
                  "none | mean | linear, per segment (default linear; mean with --whole-record, where linear biases "
                  "the response)");
  cmd->add_option("--estimator", f->estimator,
                  "h1 | h2 (Welch) | lpm | lrm (local polynomial / rational method on the whole record, "
                  "docs/estimators.md) | robust (periodic excitation, --period-samples: noise and nonlinear "
                  "distortion apart, each log one random-phase realisation)")->capture_default_str();
  cmd->add_option("--local-half-width", f->local.half_width,
                  "lpm/lrm: bins either side of each estimate (0: 6 for lpm, 7 for lrm)")->capture_default_str();
  cmd->add_option("--local-order", f->local.order, "lpm/lrm: order of the local polynomials (lrm: numerators)")->capture_default_str();
  cmd->add_option("--local-denominator-order", f->local.denominator_order, "lrm: order of the local denominator")->capture_default_str();
  cmd->add_option("--local-differences", f->local.differences,
                  "lpm/lrm: times the output is differenced first (2: the rigid body's poles at z = 1 removed)")->capture_default_str();
  cmd->add_option("--fmin", f->welch.fmin_hz, "lowest frequency kept [Hz]")->capture_default_str();
  cmd->add_option("--fmax", f->welch.fmax_hz, "highest frequency kept [Hz], clipped below Nyquist")->capture_default_str();
  cmd->add_option("--reference-column", f->reference_column, "closed loop: column/variable of the logged excitation r (H = S_ry/S_ru)");
  cmd->add_option("--reference-dataset", f->reference_dataset, "closed loop: HDF5 dataset of the logged excitation r");
  cmd->add_flag("--whole-record", f->whole_record, "each log one rectangular segment; std from the scatter between logs");
  cmd->add_option("--period-samples", f->period_samples,
                  "with --whole-record: one segment per period of this many samples (periodic excitation); with "
                  "--estimator robust: the multisine's period");
  cmd->add_option("--transient-periods", f->transient_periods,
                  "--estimator robust: whole periods dropped at the start of each log (the transient)")
      ->capture_default_str();
}

void AddUnitsFlag(CLI::App* cmd, std::string* units) {
  cmd->add_option("--units", *units,
                  "labels: rotary (kg m^2, N m s/rad) | linear (kg, N s/m); default: what the log's header says "
                  "(N m, rad: rotary; N, m: linear), else rotary");
}

bool LinearUnits(const std::string& units) { return io::ParseUnitsWord(units, "--units"); }

analysis::LogsEstimateOptions EstimateFlags::Options(bool for_fit) const {
  analysis::LogsEstimateOptions o;
  o.select = select;
  o.welch = Resolve();
  if (IsLocal()) o.local = ResolveLocal();
  o.reference_column = reference_column;
  o.reference_dataset = reference_dataset;
  o.whole_record = whole_record;
  o.period_samples = period_samples;
  try {
    analysis::ChooseRobust(&o, IsRobust(), transient_periods);
  } catch (const InputError& e) {
    throw InputError(io::WithFlags(e.what()));
  }
  o.for_fit = for_fit;
  return o;
}

}  // namespace zwidth::flags
