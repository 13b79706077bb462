// `zwidth batch`'s request and its end (flags/batch_request.h): the command's
// declarations, the checks of its flags and manifest columns, the options
// key, the previous table and the batch's end, for the command and Python.
#include "flags/batch_request.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include "analysis/batch.h"
#include "flags/flag_guard.h"
#include "io/atomic_file.h"
#include "io/model_json.h"
#include "io/option_names.h"
#include "io/printable.h"
#include "io/provenance.h"
#include "model/error.h"
#include "model/parallel.h"
#include "report/fleet_report.h"
#include "report/run_report.h"

namespace zwidth::flags {
namespace {

// Flags that say where and how fast, not what is computed: left out of the
// options hashed for resume.
const std::set<std::string>& NotHashed() {
  static const std::set<std::string> s = {"logs", "--manifest", "--output", "--unit-folders", "--jobs", "--restart", "--population", "--fleet-report", "--outlier-quantile",
                                          "--help"};
  return s;
}

// The options as typed (every flag given, in declaration order): what a
// unit's inputs are hashed with. A default changed by a new version is
// caught by the version, hashed beside (analysis::RunBatch).
std::string OptionsKey(const CLI::App* cmd) {
  std::string key;
  for (const CLI::Option* opt : cmd->get_options()) {
    if (opt->count() == 0 || NotHashed().count(opt->get_name())) continue;
    key += opt->get_name() + "=";
    for (const std::string& r : opt->results()) key += r + ",";
    key += "\n";
  }
  return key;
}

// The unit's log flags (a manifest's columns) over the command's, parsed by
// run's own declarations (AddLogFlags, GuardNumericFlags): a column is checked
// as the flag is.
io::LogSelect UnitSelect(const io::LogSelect& base, const io::BatchEntry& e) {
  io::LogSelect s = base;
  if (e.flags.empty()) return s;
  CLI::App app("the unit's log flags");
  AddLogFlags(&app, &s);
  GuardNumericFlags(&app);
  std::vector<std::string> args;
  for (const auto& [k, v] : e.flags) args.push_back("--" + k + "=" + v);
  std::reverse(args.begin(), args.end());  // CLI11 takes them last first
  try {
    app.parse(args);
  } catch (const CLI::ParseError& err) {
    std::string cols;
    for (const auto& [k, v] : e.flags) cols += (cols.empty() ? "" : ", ") + k;
    throw InputError(e.origin + " (columns " + io::Printable(cols) + "): " + err.what() +
                     "; a manifest's columns after serial and path are log flags without their dashes (rate, "
                     "input-column, output-column, time-column, input-scale, output-scale, ...), see zwidth run --help");
  }
  return s;
}

// A serial as a folder name: letters, digits, '.', '_' and '-', not starting with '.'.
void CheckFolderName(const io::BatchEntry& e) {
  const bool plain = !e.serial.empty() && e.serial[0] != '.' && e.serial.size() <= 200 &&
                     e.serial.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") ==
                         std::string::npos;
  if (!plain) {
    throw InputError("serial '" + io::Printable(e.serial) + "' (" + e.origin + ") cannot name a folder of --unit-folders: " +
                     "use letters, digits, '.', '_' and '-' (not first '.'), or give a manifest with such serials");
  }
}

}  // namespace

std::shared_ptr<BatchRequest> PrepareBatch(BatchFlags& b, const CLI::App* cmd, const std::string& command_line) {
  RunFlags& f = b.run;
  if (b.logs.empty() == b.manifest.empty()) {
    throw InputError("batch takes logs (paths or quoted globs) or --manifest units.csv, not both and not neither");
  }
  auto req = std::make_shared<BatchRequest>();
  analysis::RunInput ref;  // the reference, read once
  analysis::BatchOptions& o = req->options;
  // --reference DESIGN.json: the design's model is the reference, its tolerances the specs.
  std::optional<io::Design>& design = req->design;
  if (!f.reference.empty() && io::IsDesignFile(f.reference)) {
    design = io::ReadDesign(f.reference);
    f.reference.clear();
  }
  o.run = ResolveRunOptions(&f, &ref);
  if (design) {
    ref.reference = design->model;
    ref.reference_name = design->model_name;
    ref.reference_is_table1 = design->model_is_table1;
    io::ModelFile dm = design->model;
    std::string note;
    const double T = io::ResolveModelPeriod(std::nullopt, &dm, &note);
    o.specs = analysis::DesignSpecs(*design, analysis::ReferenceStabilityOf(dm, T, o.run.delays));
  }
  for (const std::string& s : b.specs) o.specs.push_back(analysis::ParseBatchSpec(s, o.run.delays));
  req->units = b.manifest.empty() ? io::EntriesFromArguments(b.logs) : io::ReadManifest(b.manifest);
  std::vector<std::string> inputs;
  for (const io::BatchEntry& e : req->units) {
    UnitSelect(f.est.select, e);  // every column checked before any work
    if (!b.unit_folders.empty()) CheckFolderName(e);
    inputs.push_back(e.path);
  }
  io::CheckOutputPath(b.table, inputs);
  io::CheckOutputKind(b.table, "a table (CSV, or HDF5 for .h5)", io::kCsvOrHdf5Extensions);
  if (!b.unit_folders.empty() && !std::filesystem::is_directory(b.unit_folders)) {
    throw InputError("--unit-folders " + io::Printable(b.unit_folders) + ": not a folder; create it first");
  }
  for (const std::string* out : {&b.population, &b.fleet_report}) {
    if (out->empty()) continue;
    io::CheckOutputPath(*out, inputs);
    if (out == &b.population) io::CheckOutputKind(*out, "a population table (CSV, or HDF5 for .h5)", io::kCsvOrHdf5Extensions);
    else io::CheckOutputKind(*out, "an HTML report", {".html", ".htm"});
    if (*out == b.table) throw InputError(io::Printable(*out) + " is named by -o and by --population or --fleet-report; give each its own file");
  }
  if (!b.population.empty() && b.population == b.fleet_report) {
    throw InputError("--population and --fleet-report name one file " + io::Printable(b.population) + "; give each its own");
  }
  {
    std::string why;
    if (!b.population_options.IsValid(&why)) throw InputError(why);
  }
  if (b.jobs < 0) throw InputError("--jobs " + std::to_string(b.jobs) + ": must be >= 1 (0: the cores available)");
  // Units at once: at most the cores (affinity, cgroup quota).
  const int cores = NumThreads();
  o.threads = b.jobs > 0 ? std::min(b.jobs, cores) : cores;
  o.options_key = OptionsKey(cmd);
  // Each unit is run's pipeline (analysis::AnalyseUnit) with run's estimate,
  // fit and friction options; a unit's manifest columns are its log flags.
  o.estimate_fit = {f.est.Options(true), f.fit.o};
  o.estimate_fit.friction = analysis::FrictionModelNamed(f.friction);
  if (!f.units.empty()) o.estimate_fit.linear = o.run.linear;  // else each log's header says (io::LinearUnitsOf)
  o.loop = RunLoop(f);
  o.reference = ref.reference;
  o.reference_name = ref.reference_name;
  o.reference_is_table1 = ref.reference_is_table1;
  o.words = io::WithFlags;  // the table and the unit folders show the CLI's flags
  req->unit_options = [select = f.est.select](const io::BatchEntry& e, analysis::EstimateFitOptions* eo) {
    eo->estimate.select = UnitSelect(select, e);
  };
  // A unit's files name its own log (and what the batch read before its units: a manifest, a
  // reference), not the logs other threads read meanwhile.
  if (!b.unit_folders.empty()) {
    req->unit_done = [batch_inputs = io::NotedInputs(), folders = b.unit_folders, command_line](
                         const io::BatchEntry& e, const analysis::RunAnalysis& a) {
      std::vector<std::string> inputs = batch_inputs;
      inputs.push_back(e.path);
      io::ProvenanceInputsScope scope(std::move(inputs));
      io::OutputFolder folder((std::filesystem::path(folders) / e.serial).string(), true);
      report::WriteRunReport(a, folder, {.draw_figures = false, .fit_report = FitReport(a.input.fit), .command_line = command_line});
      folder.Commit();
    };
  }
  req->table = b.table;
  req->population = b.population;
  req->fleet_report = b.fleet_report;
  req->population_options = b.population_options;
  req->restart = b.restart;
  req->jobs = b.jobs;
  req->command_line = command_line;
  return req;
}

CLI::App* DeclareBatch(CLI::App& app, const std::shared_ptr<BatchFlags>& b) {
  CLI::App* cmd = app.add_subcommand("batch", "run's estimate, fit and Z-width for many units into one table; resumes");
  cmd->add_option("logs", b->logs, "one log per unit: paths or quoted globs ('line/*.h5'), the serial is the path");
  cmd->add_option("--manifest", b->manifest,
                  "CSV of units: serial,path[,log flags without dashes: rate, input-column, ...], a row per unit");
  cmd->add_option("-o,--output", b->table, "the table to write: CSV, or HDF5 when it ends .h5/.hdf5 (docs/fleet.md); an existing one of an "
                  "earlier batch is resumed")
      ->required();
  cmd->add_option("--unit-folders", b->unit_folders, "also write each unit's run files (no figures) into FOLDER/<serial>");
  cmd->add_option("--jobs", b->jobs, "units at once (default, and at most: the cores available)")->capture_default_str();
  cmd->add_option("--spec", b->specs,
                  "end-of-line spec, repeatable: COLUMN>=BOUND or COLUMN<=BOUND (d2_K_cr_max>=1.5, m<=2e-4): "
                  "a verdict per unit (pass, marginal: within noise of a limit, fail) from the value and its std");
  cmd->add_option("--population", b->population,
                  "also write the population's table (CSV, or HDF5 for .h5): per parameter and figure its median and MAD sigma");
  cmd->add_option("--fleet-report", b->fleet_report,
                  "also write the fleet report: one self-contained HTML (distributions, every unit's region over "
                  "the design's, failures and outliers)");
  cmd->add_option("--outlier-quantile", b->population_options.outlier_quantile,
                  "a unit is an outlier when its robust Mahalanobis D^2 exceeds chi-square's quantile at this "
                  "probability (docs/fleet.md)")->capture_default_str();
  cmd->add_flag("--restart", b->restart, "compute every unit, ignoring the rows of an existing table");
  AddRunAnalysisFlags(cmd, &b->run);
  AddFrictionFlag(cmd, &b->run.friction);
  cmd->get_option("--reference")
      ->description("compare with table1 or a model JSON, or judge every unit against a design: DESIGN.json "
                    "({\"format\": \"zwidth-design\", \"model\": ..., \"tolerances\": [...]}, docs/fleet.md)");
  return cmd;
}

io::BatchTable PreviousBatchTable(const BatchRequest& request) {
  // The table is this command's output: read without noting it as an input.
  return request.restart ? io::BatchTable{} : io::ReadPreviousBatchTable(request.table);
}

io::BatchTable FinishBatch(const BatchRequest& request, const analysis::BatchResult& result) {
  // The population of this batch's units: outliers into the table, its statistics on request.
  io::BatchTable table = result.table;
  const analysis::Population pop = analysis::AnalysePopulation(table, request.population_options);
  analysis::AddOutlierColumns(pop, &table);
  io::WriteBatchTable(request.table, table);
  if (!request.population.empty()) io::WriteBatchTable(request.population, analysis::PopulationTable(pop));
  if (!request.fleet_report.empty()) {
    io::WriteTextAtomically(request.fleet_report, report::FleetHtml(table, pop, request.design ? &*request.design : nullptr,
                                                                    request.options, request.command_line));
  }
  return table;
}

std::shared_ptr<const BatchRequest> ParseBatchRequest(const std::vector<std::string>& args, const std::string& command_line) {
  CLI::App app{"zwidth"};
  app.require_subcommand(1);
  auto b = std::make_shared<BatchFlags>();
  CLI::App* cmd = DeclareBatch(app, b);
  GuardNumericFlags(&app);
  std::shared_ptr<const BatchRequest> req;
  cmd->callback([&] { req = PrepareBatch(*b, cmd, command_line); });
  std::vector<std::string> argv_text = {"zwidth", "batch"};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  try {
    CheckListFlags(app, static_cast<int>(argv_text.size()), argv.data());
    app.parse(static_cast<int>(argv_text.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    throw InputError(std::string("batch: ") + (e.get_name() == "CallForHelp" ? "--help is for the command line" : e.what()));
  }
  return req;
}

}  // namespace zwidth::flags
