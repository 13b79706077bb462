#include <cstdio>

#include "apps/common.h"
#include "io/atomic_file.h"
#include "io/frf_file.h"

namespace zwidth::app {

void AddEstimateCommand(CLI::App& app) {
  struct Flags {
    std::vector<std::string> logs;
    std::string out;
    EstimateFlags est;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("estimate", "Welch frequency response (H1/H2), coherence and per-bin std of a log");
  cmd->add_option("logs", f->logs, "log files (text, .mat, .h5): runs of one device, spectra averaged")->required();
  cmd->add_option("-o,--output", f->out, "frequency response to write (.csv or .h5)")->required();
  AddEstimateFlags(cmd, &f->est);
  cmd->callback([f] {
    io::CheckOutputFolder(f->out, f->logs);
    const LogsEstimate e = EstimateFromLogs(f->logs, f->est);
    const ident::FrequencyResponse& r = e.response.frf;
    io::WriteFrequencyResponse(f->out, r);
    std::fprintf(stderr, "%zu samples at %g Hz, %d averages, %zu bins from %.3f to %.3f Hz -> %s\n",
                 e.total_samples, r.sample_rate_hz, r.num_averages, r.f_hz.size(),
                 r.f_hz.front(), r.f_hz.back(), f->out.c_str());
  });
}

}  // namespace zwidth::app
