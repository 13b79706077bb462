// zwidth excite: an input signal for a rig, written as a one-column log.
#include <cstdio>
#include <sstream>

#include "apps/common.h"
#include "io/printable.h"
#include "ident/excitation.h"
#include "io/atomic_file.h"
#include "model/error.h"

namespace zwidth::app {

void AddExciteCommand(CLI::App& app) {
  struct Flags {
    std::string out, kind = "multisine";
    ident::ExcitationOptions o;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("excite", "write an excitation signal (noise, multisine, chirp) for a rig to play");
  cmd->add_option("-o,--output", f->out, "one-column text log to write (the rate in a # comment line)")->required();
  cmd->add_option("--kind", f->kind, "noise (band-limited) | multisine (Schroeder phases) | chirp (logarithmic)")->capture_default_str();
  cmd->add_option("--seconds", f->o.seconds, "length [s] (a multisine keeps whole periods)")->capture_default_str();
  cmd->add_option("--rate", f->o.sample_rate_hz, "sample rate [Hz]")->capture_default_str();
  cmd->add_option("--rms", f->o.rms, "RMS [input unit, e.g. N m]")->capture_default_str();
  cmd->add_option("--fmin", f->o.fmin_hz, "band start [Hz]; the multisine's line spacing")->capture_default_str();
  cmd->add_option("--fmax", f->o.fmax_hz, "band end [Hz], below Nyquist")->capture_default_str();
  AddSeedOption(cmd, &f->o.seed, "random seed (noise; a multisine's --random-phases)");
  cmd->add_flag("--random-phases", f->o.random_phases,
                "multisine: random phases from --seed instead of Schroeder's (one realisation per seed, for "
                "estimate --estimator robust)");
  cmd->callback([f] {
    if (!ident::FromString(f->kind, &f->o.kind)) {
      throw InputError("--kind '" + f->kind.substr(0, 20) + "' is not one of noise, multisine, chirp");
    }
    io::CheckOutputFolder(f->out);
    io::CheckOutputKind(f->out, "a one-column text log", io::kCsvExtensions);
    const ident::Excitation e = ident::MakeExcitation(f->o);
    std::ostringstream os;
    os.precision(17);
    os << "# zwidth excite: kind=" << ident::ToString(f->o.kind) << " rate_hz=" << e.sample_rate_hz
       << " fmin_hz=" << f->o.fmin_hz << " fmax_hz=" << f->o.fmax_hz << " rms=" << e.rms;
    if (f->o.kind == ident::ExcitationKind::kMultisine) {
      os << " period_samples=" << e.period_samples << " periods=" << e.num_periods;
      if (f->o.random_phases) os << " random_phases=1 seed=" << f->o.seed;
    }
    if (f->o.kind == ident::ExcitationKind::kNoise) os << " seed=" << f->o.seed;
    os << "\nu\n";
    for (double v : e.signal) os << v << "\n";
    io::WriteTextAtomically(f->out, os.str());
    std::printf("%s: %zu samples at %g Hz (%.6g s), rms %.6g, crest factor %.4f, %.6f of the power in %g..%g Hz",
                ident::ToString(f->o.kind).c_str(), e.signal.size(), e.sample_rate_hz,
                e.signal.size() / e.sample_rate_hz, e.rms, e.crest_factor, e.band_power_fraction, f->o.fmin_hz,
                f->o.fmax_hz);
    if (f->o.kind == ident::ExcitationKind::kMultisine) {
      std::printf("; %d lines every %.6g Hz, %d periods of %d samples", e.num_lines, e.line_spacing_hz,
                  e.num_periods, e.period_samples);
    }
    std::printf(" -> %s\n", io::Printable(f->out).c_str());
  });
}

}  // namespace zwidth::app
