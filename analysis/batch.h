// `zwidth batch` as data: many units (a device's log each), each estimated,
// fitted and analysed as `run` does it (analysis::Analyse after the caller's
// estimate and fit), into one table of text cells, one row per unit. A unit
// that fails is a row with its error and never stops the others; a unit whose
// inputs and options hash as in a previous table is taken from it (resume).
// Units run on `threads` threads, each unit's own work on its thread alone
// (ScopedSerialThread), so the process stays at that count; each unit writes
// only its slot, so the table never depends on timing. Prints nothing.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "analysis/run.h"
#include "io/batch_table.h"

namespace zwidth::analysis {

struct BatchOptions {
  RunOptions run;            // per unit, as `run`'s (figures are not computed)
  int threads = 0;           // units at once, >= 0; 0 = NumThreads() (model/parallel.h)
  std::string options_key;   // the options as text: hashed with each unit's log bytes (io::HashInputs)
  // A previous table (e.g. this batch's output from an interrupted run): a
  // unit whose serial has a row there with the same input_hash is taken from
  // it instead of being computed. Empty: every unit is computed.
  io::BatchTable previous;
  bool IsValid(std::string* why) const;
};

// The caller's estimate and fit of one unit (reading the log with its flags
// and fitting, as `run` does; apps/cmd_batch.cc): the RunInput Analyse takes,
// on a copy of BatchOptions::run that it may complete from the log (the
// loop's period). Throws InputError / ComputationError for the unit's row.
using BatchEstimateFit = std::function<RunInput(const io::BatchEntry&, RunOptions* options)>;
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
//   input_hash, sample_rate_hz, fit_quality, fit_reasons (codes, ';'), warnings (' | '),
//   m, m_std, b, b_std, delay_samples, modes, mode<i>_{omega,c,v,d}[_std] (i from 1),
//   per delay d: d<d>_{K_cr_at_zero_B, K_cr_max, B_t, B_max}[_std], d<d>_B_max_from_zero.
// Columns in that order (BatchColumns) over the rows given.
std::map<std::string, std::string> BatchRowOf(const io::BatchEntry& unit, const std::string& input_hash,
                                              const RunAnalysis& a);
std::vector<std::string> BatchColumns(const std::vector<std::map<std::string, std::string>>& rows);
// The table of the rows finished so far (those set), columns by BatchColumns.
io::BatchTable BatchTableOf(const std::vector<std::optional<std::map<std::string, std::string>>>& rows);

// Throws InputError for invalid options (before any unit); a unit's errors go to its row.
BatchResult RunBatch(const std::vector<io::BatchEntry>& units, const BatchOptions& options,
                     const BatchEstimateFit& estimate_fit, const BatchUnitDone& unit_done = {},
                     const BatchOnProgress& on_progress = {});

}  // namespace zwidth::analysis
