#include "flags/run_flags.h"

#include "model/error.h"

namespace zwidth::flags {

analysis::RunOptions ResolveRunOptions(RunFlags* f, analysis::RunInput* in) {
  f->fit.Resolve(f->est.welch.fmin_hz, f->est.welch.fmax_hz);
  analysis::RunOptions o;
  if (!f->units.empty()) o.linear = LinearUnits(f->units);  // the word checked before anything is read
  o.delays = f->delays;
  o.grid = f->grid;
  o.report_filter_hz = f->report_filter_hz;
  o.figures = !f->no_figures;
  if (f->table2) o.table2 = f->table2_options;
  for (int d : f->delays) if (d < 0) throw InputError("--delays must be >= 0");
  if (!f->reference.empty()) {
    in->reference = ReadReference(f->reference, &in->reference_is_table1);
    in->reference_name = f->reference;
  }
  if (f->loop.hands.size() > 1) throw InputError("run takes one --hand (boundary takes several)");
  std::string why;  // before anything is read or written
  if (!o.IsValid(&why)) throw InputError(why);
  return o;
}

analysis::LoopForPeriod RunLoop(const RunFlags& f) {
  return [loop = f.loop](double period_s) { return ResolveLoops(loop, period_s)[0]; };
}

void AddRunAnalysisFlags(CLI::App* cmd, RunFlags* f) {
  cmd->add_option("--reference", f->reference, "compare with: table1 (the paper's PHANToM, built in) or a model JSON (default: no comparison)");
  cmd->add_option("--delays", f->delays, "loop delays [samples]")->delimiter(',')->capture_default_str();
  AddFitFlags(cmd, &f->fit);
  cmd->add_option("--b-step", f->grid.b_step, "B step of the boundary [N m s/rad] (wins over --b-points)");
  cmd->add_option("--b-points", f->grid.b_points, "B values of the boundary, 0 to 1.05 x the largest stable B")
      ->capture_default_str();
  cmd->add_option("--report-filter-hz", f->report_filter_hz,
                  "the report's loop figure: region also with a first-order velocity low-pass at this cut-off [Hz]")
      ->capture_default_str();
  AddLoopFlags(cmd, &f->loop);
  AddEstimateFlags(cmd, &f->est);
  AddUnitsFlag(cmd, &f->units);
}

}  // namespace zwidth::flags
