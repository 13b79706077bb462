// `zwidth batch`'s request and its end, below apps so that the command
// (apps/cmd_batch.cc) and Python's zwidth.batch (python/bind_batch.cc, which
// computes the units itself, on threads or dask workers) call the same code:
// the flags parsed by the command's own declarations (the option table,
// DeclareBatch) into the units and analysis::BatchOptions (so both take the
// same flags and hash the same options key for resume), the previous table,
// and the end of a batch (the population's outlier columns, the table,
// --population and --fleet-report written).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis/batch.h"
#include "analysis/population.h"
#include "io/batch_table.h"
#include "io/design_file.h"
#include "flags/run_flags.h"

namespace zwidth::flags {

struct BatchRequest {
  // The options of every unit: the specs (--spec and a design's), the estimate,
  // fit, friction, loop, reference, the options key as typed, threads from
  // --jobs (at most the cores). previous is left empty (PreviousBatchTable).
  analysis::BatchOptions options;
  std::vector<io::BatchEntry> units;        // from the arguments or --manifest, checked
  analysis::BatchUnitOptions unit_options;  // a unit's manifest columns as its log flags
  analysis::BatchUnitDone unit_done;        // --unit-folders: the unit's run files; else empty
  std::optional<io::Design> design;         // --reference DESIGN.json
  std::string table;                        // -o
  std::string population, fleet_report;     // "" when not asked
  analysis::PopulationOptions population_options;
  bool restart = false;
  int jobs = 0;                             // --jobs as given (0: the cores)
  // How the batch was asked for (the unit folders' report.html, the fleet
  // report): the command line, or Python's call.
  std::string command_line;
};

// batch's flags as declared (DeclareBatch) and given.
struct BatchFlags {
  RunFlags run;
  std::vector<std::string> logs;
  std::string manifest, table, unit_folders, population, fleet_report;
  analysis::PopulationOptions population_options;
  std::vector<std::string> specs;
  int jobs = 0;
  bool restart = false;
};

// `batch` declared on `app` (its flags into *b), and the request of the flags
// as parsed: everything checked and read before any unit is computed
// (InputError naming the flag). command_line: BatchRequest::command_line.
CLI::App* DeclareBatch(CLI::App& app, const std::shared_ptr<BatchFlags>& b);
std::shared_ptr<BatchRequest> PrepareBatch(BatchFlags& b, const CLI::App* cmd, const std::string& command_line);

// `batch`'s arguments (those after "zwidth batch") as the command parses them:
// its declarations, the numeric and list checks, every manifest column checked,
// the output paths, the design and reference read. InputError naming the flag
// (a CLI11 parse error's message, --help included) before any unit is computed.
std::shared_ptr<const BatchRequest> ParseBatchRequest(const std::vector<std::string>& args,
                                                      const std::string& command_line);

// The table at -o to resume from (io::ReadPreviousBatchTable); empty with --restart.
io::BatchTable PreviousBatchTable(const BatchRequest& request);

// The batch's end: the population of its ok units (outlier columns into the
// table), the table written at -o, --population and --fleet-report. Returns
// the table as written.
io::BatchTable FinishBatch(const BatchRequest& request, const analysis::BatchResult& result);

}  // namespace zwidth::flags
