// `zwidth batch` as data: many units (a device's log each), each estimated,
// fitted and analysed by `run`'s pipeline (analysis::EstimateFitAndAnalyse:
// the same friction rule, the same numbers), into one table of text cells, one row per unit. A unit
// that fails is a row with its error and never stops the others; a unit whose
// inputs and options hash as in a previous table is taken from it (resume).
// Units run on `threads` threads, each unit's own work on its thread alone
// (ScopedSerialThread), so the process stays at that count; each unit writes
// only its slot, so the table never depends on timing. Prints nothing.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "analysis/run.h"
#include "analysis/run_input.h"
#include "io/batch_table.h"
#include "io/design_file.h"

namespace zwidth::analysis {

// One end-of-line spec on a column of the table: "d2_K_cr_max>=1.5" (K_CR^max
// at delay 2 at least 1.5 N m/rad), "m<=2e-4". A unit meets it with the
// probability P = Phi((value - bound) / std) for >= (Phi((bound - value) / std)
// for <=), its std the column's "_std" (the delta method); no std: P = 1 when
// the value meets it, else 0.
struct BatchSpec {
  std::string column;          // a numeric column: m, b, mode<i>_<field>, d<d>_<figure> (a delay of the run)
  bool at_least = true;        // >= (else <=)
  double bound = 0.0;          // finite
  std::string text;            // as given
};
// Parses "COLUMN>=BOUND" or "COLUMN<=BOUND"; InputError naming the spec and
// the columns it may name (delays: the run's).
BatchSpec ParseBatchSpec(const std::string& text, const std::vector<int>& delays);
// The verdict of a row's cells (status ok) against the specs: sets "verdict"
// (pass: every spec met with P >= 0.95; fail: some spec with P <= 0.05;
// marginal: else, within noise of a limit; fail too when the row's
// fit_quality is poor, whatever P), "verdict_reasons" (each spec not
// surely met, with value, std and P) and "p_min" (the least P). Nothing
// without specs.
// Also "p_<column>_min" (a >= spec) or "p_<column>_max" (<=): each spec's P.
// Replaces the verdict columns a row had (a resumed row is judged again).
void ApplySpecs(const std::vector<BatchSpec>& specs, std::map<std::string, std::string>* cells);

// The specs of a design's tolerances (io/design_file.h, `--reference
// DESIGN.json`): min / max as they are; relative and absolute ones around the
// design's value, a parameter's from the design's model, a figure's from
// `design_zwidth` (the design model's Z-width per delay of the run,
// ReferenceStabilityOf). InputError naming the tolerance (file, line) for a
// figure at a delay the run does not compute, a mode the design lacks, or a
// design figure that is not finite.
std::vector<BatchSpec> DesignSpecs(const io::Design& design, const ReferenceStability& design_zwidth);

// The unit's own options over BatchOptions::estimate_fit (e.g. its log flags
// from a manifest's columns, apps/cmd_batch.cc); InputError for the unit's row.
using BatchUnitOptions = std::function<void(const io::BatchEntry&, EstimateFitOptions* options)>;

struct BatchOptions {
  std::vector<BatchSpec> specs;  // end-of-line specs (ApplySpecs); none: no verdict columns
  RunOptions run;            // per unit, as `run`'s (figures are not computed)
  // Per unit, as `run`'s: the estimate, the fit and the friction
  // (EstimateFitOptions::friction, auto as `run --friction`'s default);
  // reference_thread is not used (the reference's Z-width is computed on the
  // unit's thread, so the process stays at `threads` threads).
  EstimateFitOptions estimate_fit;
  LoopForPeriod loop;        // the run's loop at a unit's period; run.loop when empty
  // Each unit compared with it on the paper's loop, as `run --reference`
  // (RunInput::reference and its names).
  std::optional<io::ModelFile> reference;
  std::string reference_name;
  bool reference_is_table1 = false;
  // The library's texts in the caller's words (FitMessages::words): the
  // warnings column and the unit folders' files.
  std::function<std::string(const std::string&)> words;
  int threads = 0;           // units at once, >= 0; 0 = NumThreads() (model/parallel.h)
  // The options as text: hashed with each unit's log bytes (io::HashInputs),
  // beside the version, the unit's flags and the friction model (an options
  // field whose default a caller does not spell out).
  std::string options_key;
  // A previous table (e.g. this batch's output from an interrupted run): a
  // unit whose serial has a row there with the same input_hash is taken from
  // it instead of being computed. Empty: every unit is computed.
  io::BatchTable previous;
  bool IsValid(std::string* why) const;
};

// The unit's input_hash (FNV-1a, io::HashInputs): its log's bytes with the
// options key, the zwidth version, the friction model and the unit's own
// flags. A previous row with this hash is taken instead of computing the unit
// (resume); "" when the log cannot be read (the unit is computed, its error a row).
std::string UnitInputHash(const io::BatchEntry& unit, const BatchOptions& options);

// One unit's analysis from its log (logs = {unit.path}), as RunBatch computes
// it: EstimateFitAndAnalyse (analysis/run_input.h), the pipeline of `run`,
// with the batch's options (the unit's own over them), quiet. Throws
// InputError / ComputationError for the unit's row.
RunAnalysis AnalyseUnit(const io::BatchEntry& unit, const BatchOptions& options,
                        const BatchUnitOptions& unit_options = {});

// How the batch engine computes a unit (RunBatchWith): AnalyseUnit for
// RunBatch; a test of the engine (resume, threads, errors) gives its own.
using BatchComputeUnit = std::function<RunAnalysis(const io::BatchEntry&, const RunOptions& options)>;
// Called on the unit's thread after its analysis (e.g. to write its folder);
// an exception makes the unit's row an error.
using BatchUnitDone = std::function<void(const io::BatchEntry&, const RunAnalysis&)>;

struct BatchProgress {
  size_t total = 0;     // units in the batch
  size_t done = 0;      // units finished (computed, failed or resumed)
  size_t computed = 0;  // of done: computed now (ok or failed)
  size_t failed = 0;    // of done: rows with an error (resumed ones included)
  size_t resumed = 0;   // of done: taken from the previous table
  double elapsed_s = 0.0;
  // Units per second computed now and the seconds left at that rate (nan before the first).
  double rate_per_s() const;
  double seconds_left() const;
};
// Called after each unit under one lock (never two at once), with the rows
// finished so far (nullopt: not yet): a caller shows progress and saves the
// table now and then (BatchTableOf) so an interruption loses little.
using BatchOnProgress =
    std::function<void(const BatchProgress&, const std::vector<std::optional<std::map<std::string, std::string>>>&)>;

struct BatchResult {
  io::BatchTable table;  // one row per unit, in the units' order
  BatchProgress progress;
};

// The row's cells, by column (FormatBatchCsv writes them; %.17g, so a cell
// reads back as the double `run` wrote):
//   serial, logs, status (ok | input_error | computation_error), error,
//   verdict, verdict_reasons, p_min (with specs),
//   input_hash, sample_rate_hz, units (rotary | linear: the model's, model/units.h), fit_quality, fit_reasons (codes, ';'), warnings (' | '),
//   m, m_std, b, b_std, delay_samples, modes,
//   friction_status (fitted | not detected | not identified: fit.friction.status; empty when not looked at),
//   friction_topology (rigid body | collocated, when fitted),
//   F_c, F_c_std, friction_offset, friction_offset_std (the model's friction: F_c its Coulomb level,
//   coulomb_pos = coulomb_neg; 0 without std when none was found; empty when not looked at),
//   linear_only_b, linear_only_b_std (the linear-only fit's b, when the friction was looked at),
//   mode<i>_{omega,c,v,d}[_std] (i from 1),
//   per delay d: d<d>_{K_cr_at_zero_B, K_cr_max, B_t, B_max}[_std], d<d>_B_max_from_zero.
// Columns in that order (BatchColumns) over the rows given.
std::map<std::string, std::string> BatchRowOf(const io::BatchEntry& unit, const std::string& input_hash,
                                              const RunAnalysis& a);
std::vector<std::string> BatchColumns(const std::vector<std::map<std::string, std::string>>& rows);
// The table of the rows finished so far (those set), columns by BatchColumns.
io::BatchTable BatchTableOf(const std::vector<std::optional<std::map<std::string, std::string>>>& rows);

// The rows finished so far saved at `path` (io::WriteBatchTable of
// BatchTableOf: atomic, a resumable table) now and then while a batch runs, so
// that a batch killed midway keeps its finished units: `zwidth batch` and
// Python's zwidth.batch call it after each unit (a BatchOnProgress). A save
// when `interval_s` has passed since the start or the last save and units are
// left (the batch's end writes the whole table); Save() at once (an interrupt).
class BatchTableSaver {
 public:
  static constexpr double kDefaultIntervalS = 2.0;
  explicit BatchTableSaver(std::string path, double interval_s = kDefaultIntervalS);
  void operator()(const BatchProgress& progress,
                  const std::vector<std::optional<std::map<std::string, std::string>>>& rows);
  void Save(const std::vector<std::optional<std::map<std::string, std::string>>>& rows);

 private:
  std::string path_;
  double interval_s_;
  std::chrono::steady_clock::time_point last_;
};

// Every unit by AnalyseUnit. Throws InputError for invalid options (before
// any unit); a unit's errors go to its row.
BatchResult RunBatch(const std::vector<io::BatchEntry>& units, const BatchOptions& options,
                     const BatchUnitOptions& unit_options = {}, const BatchUnitDone& unit_done = {},
                     const BatchOnProgress& on_progress = {});
// The engine with another computation of a unit (`compute` is given
// options.run without figures); options.estimate_fit, loop and reference are
// then not used.
BatchResult RunBatchWith(const std::vector<io::BatchEntry>& units, const BatchOptions& options,
                         const BatchComputeUnit& compute, const BatchUnitDone& unit_done = {},
                         const BatchOnProgress& on_progress = {});

}  // namespace zwidth::analysis
