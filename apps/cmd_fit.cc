#include <cstdio>
#include <iostream>

#include "apps/common.h"
#include "analysis/compare.h"
#include "analysis/table2.h"
#include "apps/fit_support.h"
#include "io/atomic_file.h"
#include "io/frf_file.h"
#include "io/printable.h"
#include "io/provenance.h"
#include "io/reference_models.h"
#include "io/stability_files.h"
#include "model/error.h"

namespace zwidth::app {

void AddFitCommands(CLI::App& app) {
  struct Flags {
    std::vector<std::string> inputs;
    std::string out, init, units, friction = "auto";  // units "": the log header's, else rotary
    EstimateFlags est;
    FitFlags fit;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("fit", "fit the parameters of eq. (1) to a log or a saved frequency response");
  cmd->add_option("input", f->inputs, "logs (text, .mat, .h5; several runs averaged) or one frequency response from `zwidth estimate`")->required();
  cmd->add_option("-o,--output", f->out, "model JSON to write")->required();
  AddFitFlags(cmd, &f->fit);
  cmd->add_option("--init", f->init, "model JSON to start from (tried before the automatic starts)");
  cmd->add_option("--starts", f->fit.o.max_starts, "automatic starts tried")->capture_default_str();
  cmd->add_option("--max-iterations", f->fit.o.max_iterations, "solver iterations per start")->capture_default_str();
  AddEstimateFlags(cmd, &f->est);
  AddUnitsFlag(cmd, &f->units);
  AddFrictionFlag(cmd, &f->friction);
  cmd->callback([f] {
    std::vector<std::string> read = f->inputs;
    if (!f->init.empty()) read.push_back(f->init);
    io::CheckOutputFolder(f->out, read);
    io::CheckOutputKind(f->out, "a model JSON", {".json"});
    f->fit.Resolve(f->est.welch.fmin_hz, f->est.welch.fmax_hz);
    const fit::FrictionModel friction_model = analysis::FrictionModelNamed(f->friction);
    const std::optional<bool> units_given =
        f->units.empty() ? std::nullopt : std::optional<bool>(LinearUnits(f->units));
    const std::string source = JoinPaths(f->inputs);
    if (!f->init.empty()) f->fit.o.init = io::ReadModelJsonFor(f->init, "fit --init").plant;
    StageTimer timer(false);
    const bool frf_file = f->inputs.size() == 1 && io::IsFrequencyResponseFile(f->inputs[0]);
    if (f->inputs.size() > 1) {
      for (const std::string& in : f->inputs) {
        if (io::IsFrequencyResponseFile(in)) {
          throw InputError(in + " is a saved frequency response: a saved frequency response can only be fitted "
                           "alone (fit one response, or fit the runs' logs together, which averages their spectra)");
        }
      }
    }
    std::string friction_warning;
    std::optional<FrictionInput> fin =
        analysis::FrictionInputFor(f->inputs, frf_file, f->est.select, f->est.Resolve(), friction_model, &friction_warning);
    if (!friction_warning.empty()) std::fprintf(stderr, "warning: %s\n", WithFlags(friction_warning).c_str());
    std::string frf_note;
    std::vector<io::LogInfo> infos;  // a saved response: no header to read units from
    ident::FrequencyResponse frf;
    if (frf_file) {
      frf = io::ReadFrequencyResponse(f->inputs[0], f->est.select.sample_rate_hz, &frf_note);
    } else {
      analysis::LogsEstimate est = EstimateFromLogs(f->inputs, f->est, true);
      frf = std::move(est.response.frf);
      infos = std::move(est.infos);
    }
    const bool linear = io::LinearUnitsOf(units_given, infos, "ModelFile::linear");  // before the fit
    if (!frf_note.empty()) std::fprintf(stderr, "note: %s\n", io::PrintableLines(frf_note).c_str());
    fit::FitResult r;
    fit::FrictionFitResult ff;
    io::ModelFile mf = FitToModelFile(frf, f->fit.o, source, linear, &r, fin ? &*fin : nullptr, &ff);
    io::WriteModelJson(f->out, mf);
    std::printf("%s", io::PrintableLines(ParameterTable(mf, linear)).c_str());
    std::printf("%s (%.1f ms)\n", r.BriefReport().c_str(), timer.Lap("fit"));
    std::printf("order: pole pairs sorted by omega, zero pairs by v (G is unchanged); sections numbered from 1\n");
    std::printf("%s", FrictionLine(ff).c_str());
    std::printf("%s", io::PrintableLines(FitReport(r)).c_str());
  });

  struct CompareFlags {
    std::string model, reference, summary;
    std::vector<int> delays = {2, 4, 8};
    double period = kNotGiven;
    bool json = false;
    bool table2 = false;
    analysis::Table2Options t2;
  };
  auto c = std::make_shared<CompareFlags>();
  CLI::App* cc = app.add_subcommand("compare", "compare a fitted model with a reference (--reference table1 or a model JSON)");
  cc->add_option("model", c->model, "model JSON")->required();
  cc->add_option("--reference", c->reference, "table1 (the paper's PHANToM model, built in) or a reference model JSON");
  cc->add_option("--delays", c->delays, "delays for the stability comparison")->delimiter(',')->capture_default_str();
  cc->add_option("--period", c->period, "sample period [s] (default: the model's, else 0.001)");
  cc->add_flag("--json", c->json, "print JSON on standard output");
  AddTable2Flags(cc, &c->table2, &c->t2);
  cc->callback([c] {
    io::ModelFile m = io::ReadModelJsonFor(c->model, "compare");  // not const: --period may convert its delay
    if (c->reference.empty() && !c->table2) {
      throw InputError("compare needs a reference: --reference table1 (Table I, the paper's PHANToM) or --reference "
                       "MODEL.json, or --table2 (the paper's measured relay points)");
    }
    if (const std::string why = io::LoopDelaysProblem(c->delays, "--delays"); !why.empty()) throw InputError(why);
    std::string why;
    if (c->table2 && !c->t2.IsValid(&why)) throw InputError(why);
    const double T = ResolvePeriod(c->period, &m);
    std::string text;
    nlohmann::json j = nlohmann::json::object();
    if (!c->reference.empty()) {
      bool table1 = false;
      io::ModelFile r = ReadReference(c->reference, &table1);
      analysis::CheckSameUnits(m.linear, r, c->model, table1 ? "Table I (--reference table1)" : c->reference);
      app::ConvertDelayToPeriod(&r, T, "the reference");
      j = CompareModels(m, r, c->delays, T, &text);
    }
    if (c->table2) {
      const analysis::Table2Comparison t2 = analysis::CompareTable2(m.plant, T, io::Table2Points(), c->t2);
      j["table2"] = analysis::Table2Json(t2);
      text += (text.empty() ? "" : "\n") + analysis::Table2Text(t2);
    }
    j["provenance"] = io::ProvenanceJson();
    if (c->json) std::cout << j.dump(2) << std::endl;
    else std::printf("%s", io::PrintableLines(text).c_str());
  });
}

}  // namespace zwidth::app
