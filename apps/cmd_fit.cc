#include <cstdio>
#include <iostream>

#include "apps/common.h"
#include "apps/fit_support.h"
#include "io/atomic_file.h"
#include "io/frf_file.h"
#include "model/error.h"

namespace zwidth::app {

void AddFitCommands(CLI::App& app) {
  struct Flags {
    std::string input, out, init;
    EstimateFlags est;
    FitFlags fit;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("fit", "fit the parameters of eq. (1) to a log or a saved frequency response");
  cmd->add_option("input", f->input, "log (.h5/.csv) or frequency response (.csv/.h5) from `zwidth estimate`")->required();
  cmd->add_option("-o,--output", f->out, "model JSON to write")->required();
  AddFitFlags(cmd, &f->fit);
  cmd->add_option("--init", f->init, "model JSON to start from (tried before the automatic starts)");
  cmd->add_option("--starts", f->fit.o.max_starts, "automatic starts tried")->capture_default_str();
  cmd->add_option("--max-iterations", f->fit.o.max_iterations, "solver iterations per start")->capture_default_str();
  AddEstimateFlags(cmd, &f->est);
  cmd->callback([f] {
    io::CheckOutputFolder(f->out);
    f->fit.Resolve(f->est.welch.fmin_hz, f->est.welch.fmax_hz);
    if (!f->init.empty()) f->fit.o.init = io::ReadModelJson(f->init).plant;
    StageTimer timer(false);
    const ident::FrequencyResponse frf = io::IsFrequencyResponseFile(f->input)
        ? io::ReadFrequencyResponse(f->input, f->est.select.sample_rate_hz)
        : EstimateFromLog(f->input, f->est);
    fit::FitResult r;
    const io::ModelFile mf = FitToModelFile(frf, f->fit.o, f->input, &r);
    io::WriteModelJson(f->out, mf);
    std::printf("%s", ParameterTable(mf).c_str());
    std::printf("%s (%.1f ms)\n", r.BriefReport().c_str(), timer.Lap("fit"));
    std::printf("order: pole pairs sorted by omega, zero pairs by v (G is unchanged); sections numbered from 1\n");
    std::printf("%s", FitReport(r).c_str());
  });

  struct CompareFlags {
    std::string model, reference, summary;
    std::vector<int> delays = {2, 4, 8};
    double period = kNotGiven;
    bool json = false;
  };
  auto c = std::make_shared<CompareFlags>();
  CLI::App* cc = app.add_subcommand("compare", "compare a fitted model with a reference (default: Table I)");
  cc->add_option("model", c->model, "model JSON")->required();
  cc->add_option("--reference", c->reference, "reference model JSON (default datasets/phantom/table1.json)");
  cc->add_option("--delays", c->delays, "delays for the stability comparison")->delimiter(',')->capture_default_str();
  cc->add_option("--period", c->period, "sample period [s] (default: the model's, else 0.001)");
  cc->add_flag("--json", c->json, "print JSON on standard output");
  cc->callback([c] {
    const io::ModelFile m = io::ReadModelJson(c->model);
    const io::ModelFile r = io::ReadModelJson(c->reference.empty() ? DefaultReferencePath() : c->reference);
    for (int d : c->delays) if (d < 0) throw InputError("--delays must be >= 0");
    const double T = ResolvePeriod(c->period, m);
    std::string text;
    const nlohmann::json j = CompareModels(m, r, c->delays, T, &text);
    if (c->json) std::cout << j.dump(2) << std::endl;
    else std::printf("%s", text.c_str());
  });
}

}  // namespace zwidth::app
