// What `zwidth run` computes after the estimate and the fit, as data: the
// model's Z-width per delay (PlantStability), the comparison with a reference,
// and the data of the report's figures (Bode with unwrapped phases, K_CR
// curves of the reference and of the rigid body, the loop figure's regions and
// passivity bounds). Prints nothing; report/ turns a RunAnalysis into files.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/compare.h"
#include "analysis/friction_amplitude.h"
#include "analysis/plant_stability.h"
#include "analysis/table2.h"
#include "fit/fit.h"
#include "fit/friction_fit.h"
#include "ident/joint.h"
#include "io/model_json.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {

struct RunOptions {
  std::vector<int> delays = {2, 4, 8};  // loop delays [samples], each >= 0, in the order reported
  stability::LoopOptions loop;          // the run's loop (velocity filter, hand); default: the paper's
  stability::BGridOptions grid;         // B grid of the boundary rows
  double report_filter_hz = 50.0;       // the loop figure's first-order velocity low-pass [Hz], > 0
  bool figures = true;                  // compute the figure data (Bode, curves, regions)
  bool linear = false;                  // labels in kg and N s/m instead of kg m^2, N m s/rad; kept in model.json
  // With a value: Table II's relay points beside the model (CompareTable2, the
  // log at 1 kHz), in summary.json's "table2" and the report; none: not computed.
  std::optional<Table2Options> table2;
  // False with *why naming the field when a field is out of range.
  bool IsValid(std::string* why) const;
};

// The reference's Z-width on the paper's loop, per delay (for the comparison
// and the K_CR figure). It needs only the reference and the log's period, so
// a caller can compute it while the fit runs (ReferenceStabilityOf).
struct ReferenceStability {
  double period_s = 0.0;                      // [s]
  std::vector<int> delays;                    // [samples], as RunOptions::delays
  std::vector<stability::ZWidth> zwidths;     // one per delay
  std::vector<stability::DelaySummary> summaries;
};
ReferenceStability ReferenceStabilityOf(const io::ModelFile& reference, double period_s, const std::vector<int>& delays);

// The estimate and the fit that a run analyses (made by the caller: reading
// logs and fitting are their own stages, shared with `estimate` and `fit`).
struct RunInput {
  ident::CombinedResponse response;          // the estimate of every log
  size_t total_samples = 0;                  // samples of all logs
  std::vector<std::string> logs;             // the log paths, in order
  std::string source;                        // the logs as one name ("a.h5 + b.h5"), as in model.json
  bool whole_record = false;                 // one segment per run (no Welch averaging)
  fit::FitResult fit;                        // the fit of response.frf (status converged)
  fit::FrictionFitResult friction_fit;       // the friction fit's (status kNotRun: not run)
  io::ModelFile model;                       // that fit as a model file
  std::optional<io::ModelFile> reference;    // compared with, on the paper's loop; none: no comparison
  std::string reference_name;                // what the reference was read from: "table1" or its path
  bool reference_is_table1 = false;          // the reference is the paper's Table I (Table II drawn)
  // The reference's Z-width when the caller computed it already (for the same
  // period and delays; Analyse checks); else Analyse computes it.
  std::optional<ReferenceStability> reference_stability;
};

// The Bode figure: measured and model (exact ZOH, without the loop's hand),
// phases unwrapped along frequency, the measured within half a turn of the model.
struct BodeData {
  std::vector<double> H_abs, H_phase_deg;  // measured, per bin of response.frf
  std::vector<double> G_abs, G_phase_deg;  // model, per bin
  // The model's std per bin from its parameter covariance (the delta method:
  // the sensitivity of ln G to the log parameters, by central differences,
  // times the covariance): of ln|G| (relative) and of its phase [deg]. Empty
  // when the model has no covariance.
  std::vector<double> G_log_abs_std, G_phase_std_deg;
};

// The loop figure of one delay: the region with the raw backward difference
// (which 0) and with the report's velocity low-pass (which 1), and the
// passivity boundary K_P(B) of each, on 300 B values from 0 to 1.05 x the
// larger B_max.
struct LoopFigureDelay {
  std::vector<double> B;                                  // N m s/rad
  std::vector<std::vector<stability::KInterval>> raw, filtered;  // per B
  std::vector<double> K_passive_raw, K_passive_filtered;  // per B [N m/rad]
};

struct FigureData {
  BodeData bode;
  std::vector<std::vector<stability::CriticalPoint>> kcr_reference;  // [delay][B]; empty without a reference
  std::vector<std::vector<stability::CriticalPoint>> kcr_rigid;      // [delay][B]: the rigid body alone
  std::vector<LoopFigureDelay> loop;                                // one per delay
};

struct RunStage {
  std::string name;  // e.g. "boundary"
  double ms = 0.0;   // wall time [ms]
};

struct RunAnalysis {
  explicit RunAnalysis(PlantStability s) : stability(std::move(s)) {}
  RunInput input;                              // response.frf.used_by_fit set from the fit's band
  RunOptions options;
  double period_s = 0.0;                       // the log's sample period [s]
  // The model on the run's loop; with Coulomb friction in the model
  // (input.model.friction) also A* along the boundary
  // (stability.friction_amplitudes, default options, no encoder step).
  PlantStability stability;
  std::optional<ModelComparison> comparison;   // with input.reference
  std::optional<FigureData> figures;           // when options.figures
  std::vector<RunStage> stages;                // stage times, in order ("figure data" last)
  std::optional<Table2Comparison> table2;      // with options.table2
};

// Throws InputError for invalid options (the field named), ComputationError
// when a computation fails.
RunAnalysis Analyse(RunInput input, const RunOptions& options);

// The verdict, its reasons with advice, the band, the delay and order
// choices, and the stabilisation table, as `fit` and `run` print it.
std::string FitReport(const fit::FitResult& r);

}  // namespace zwidth::analysis
