// zwidth run: estimate -> fit -> analysis -> report, the job a user runs on a
// new device log. This file only wires: flags -> report::RunJob (the whole
// pipeline, report::RunToFolder, which Python's zwidth.run calls too), the
// messages on stderr and the results on stdout.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/run.h"
#include "analysis/run_input.h"
#include "io/printable.h"
#include "apps/common.h"
#include "apps/fit_support.h"
#include "flags/loop_flags.h"
#include "flags/run_flags.h"
#include "io/atomic_file.h"
#include "model/error.h"
#include "report/run_report.h"

namespace zwidth::app {
namespace {

void PrintStage(const std::string& name, double ms) { std::fprintf(stderr, "  %-28s %9.3f ms\n", name.c_str(), ms); }

// The CLI's messages of a run: the estimate's lines, the fit's warnings, the
// notes and the stage times on stderr (in its flags).
analysis::RunMessages RunMessagesOfCli() {
  analysis::RunMessages m;
  m.estimate = [](const std::string& line) { std::fprintf(stderr, "%s\n", io::Printable(WithFlags(line)).c_str()); };
  m.fit.warning = [](const std::string& w) { std::fprintf(stderr, "warning: %s\n", io::Printable(WithFlags(w)).c_str()); };
  m.note = [](const std::string& n) { std::fprintf(stderr, "note: %s\n", n.c_str()); };
  m.stage = [](const std::string& name, double ms) { PrintStage(name, ms); };
  return m;
}

void Run(RunFlags& f) {
  analysis::RunInput in;
  in.logs = f.logs;
  in.source = JoinPaths(f.logs);
  analysis::RunOptions o = ResolveRunOptions(&f, &in);
  analysis::EstimateFitOptions eo{f.est.Options(true), f.fit.o};
  eo.friction = analysis::FrictionModelNamed(f.friction);
  if (!f.units.empty()) eo.linear = o.linear;  // else the logs' headers say (io::LinearUnitsOf)
  // Everything is built in a temporary sibling folder and moved into place
  // at the end (io::OutputFolder): a failure or a signal leaves nothing, and
  // two runs into one folder cannot mix.
  io::OutputFolder folder(f.outdir, f.force);
  std::fprintf(stderr, "zwidth run %s -> %s\n", io::Printable(in.source).c_str(), io::Printable(f.outdir).c_str());
  analysis::RunMessages m = RunMessagesOfCli();
  m.fit.words = WithFlags;  // the report and model.json show the CLI's flags
  report::RunJob job{std::move(in), eo, o, RunLoop(f),
                     {.draw_figures = true, .png = f.png, .fit_report = "", .command_line = CommandLine()}};
  const report::RunJobResult r = report::RunToFolder(std::move(job), folder, m);
  const analysis::RunAnalysis& a = r.analysis;
  const report::RunReport& rep = r.report;
  const std::string& fit_report = r.fit_report;
  double t_total = r.estimate_fit_ms;
  for (const analysis::RunStage& s : a.stages) {
    if (s.name.rfind("figure", 0) == 0) continue;
    PrintStage(s.name, s.ms);
    t_total += s.ms;
  }
  PrintStage(rep.stages.front().name, rep.stages.front().ms);
  PrintStage("total (figures excluded)", t_total + rep.stages.front().ms);
  for (const analysis::RunStage& s : a.stages) if (s.name.rfind("figure", 0) == 0) PrintStage(s.name, s.ms);
  for (size_t i = 1; i < rep.stages.size(); ++i) PrintStage(rep.stages[i].name, rep.stages[i].ms);
  folder.Commit();
  const std::string params = analysis::ParameterTable(a.input.model, a.options.linear);
  const std::string cmp = a.comparison ? a.comparison->text : "";
  std::printf("fit quality: %s\n%s%s\n%s", fit::ToString(a.input.fit.quality).c_str(),
              io::PrintableLines(params).c_str(), FrictionLine(a.input.friction_fit).c_str(),
              io::PrintableLines(cmp).c_str());
  std::fprintf(stderr, "%s", io::PrintableLines(fit_report).c_str());
  const std::filesystem::path final_out(folder.path());
  std::printf("\nboundary: %s (%d of %zu rows where margin() and the exact K_CR disagree)\nreport: %s\n",
              io::Printable((final_out / "boundary.csv").string()).c_str(), a.stability.margin_disagreements, a.stability.rows.size(),
              (final_out / "report.html").c_str());
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  auto f = std::make_shared<RunFlags>();
  CLI::App* cmd = app.add_subcommand("run", "estimate, fit, compare, Z-width boundary and an HTML report");
  cmd->add_option("logs", f->logs, "log files (text, .mat, .h5): runs of one device, spectra averaged")->required();
  cmd->add_option("-o,--output", f->outdir, "output folder: new, or existing and empty (its parent must exist)")->required();
  cmd->add_flag("--force", f->force, "write into a non-empty output folder, replacing zwidth's files there");
  cmd->add_flag("--no-figures", f->no_figures, "no figures/ folder, no gnuplot: the data files and the report only");
  cmd->add_flag("--png", f->png, "also draw every figure as PNG (the report uses the SVGs)")->excludes("--no-figures");
  AddRunAnalysisFlags(cmd, f.get());
  AddFrictionFlag(cmd, &f->friction);
  AddTable2Flags(cmd, &f->table2, &f->table2_options);
  cmd->callback([f] { Run(*f); });
}

}  // namespace zwidth::app
