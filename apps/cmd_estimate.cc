#include <cstdio>
#include <filesystem>
#include <sstream>

#include "apps/common.h"
#include "io/printable.h"
#include "io/atomic_file.h"
#include "io/frf_file.h"
#include "model/error.h"

namespace zwidth::app {

void AddEstimateCommand(CLI::App& app) {
  struct Flags {
    std::vector<std::string> logs;
    std::string out, coherences;
    EstimateFlags est;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("estimate", "Welch frequency response (H1/H2), coherence and per-bin std of a log");
  cmd->add_option("logs", f->logs, "log files (text, .mat, .h5): runs of one device, spectra averaged")->required();
  cmd->add_option("-o,--output", f->out, "frequency response to write (.csv or .h5)")->required();
  cmd->add_option("--coherences-output", f->coherences,
                  "CSV of f_hz, coherence u->y, and with --reference-* r->u, r->y");
  AddEstimateFlags(cmd, &f->est);
  cmd->callback([f] {
    io::CheckOutputFolder(f->out, f->logs);
    io::CheckOutputKind(f->out, "a frequency response (CSV, or HDF5 for .h5)", io::kCsvOrHdf5Extensions);
    if (!f->coherences.empty()) {
      std::vector<std::string> inputs = f->logs;
      inputs.push_back(f->out);  // an existing file named twice
      io::CheckOutputFolder(f->coherences, inputs);
      io::CheckOutputKind(f->coherences, "a coherence CSV", io::kCsvExtensions);
      std::error_code e1, e2;
      if (std::filesystem::weakly_canonical(f->coherences, e1) == std::filesystem::weakly_canonical(f->out, e2) &&
          !e1 && !e2) {
        throw InputError("--coherences-output '" + f->coherences + "' is also -o: give two different files");
      }
    }
    const LogsEstimate e = EstimateFromLogs(f->logs, f->est);
    const ident::FrequencyResponse& r = e.response.frf;
    io::WriteFrequencyResponse(f->out, r);
    if (!f->coherences.empty()) {
      const bool joint = e.response.method == ident::CombinedMethod::kJoint;
      std::ostringstream os;
      os.precision(17);
      os << "f_hz,coherence_uy" << (joint ? ",coherence_ru,coherence_ry" : "") << "\n";
      for (size_t k = 0; k < r.f_hz.size(); ++k) {
        // u->y from the averaged spectra (the FRF file's coherence column is r->y when joint).
        const double uy = std::norm(r.S_uy[k]) / (r.S_uu[k] * r.S_yy[k]);
        os << r.f_hz[k] << "," << uy;
        if (joint) os << "," << e.response.coherence_ru[k] << "," << e.response.coherence_ry[k];
        os << "\n";
      }
      io::WriteTextAtomically(f->coherences, os.str());
    }
    std::fprintf(stderr, "%zu samples at %g Hz, %d averages, %zu bins from %.3f to %.3f Hz -> %s\n",
                 e.total_samples, r.sample_rate_hz, r.num_averages, r.f_hz.size(),
                 r.f_hz.front(), r.f_hz.back(), io::Printable(f->out).c_str());
  });
}

}  // namespace zwidth::app
