#include "flags/fit_flags.h"

#include <optional>
#include <stdexcept>

#include "analysis/run.h"
#include "io/option_names.h"
#include "io/reference_models.h"
#include "model/error.h"

namespace zwidth::flags {

io::ModelFile ReadReference(const std::string& flag, bool* is_table1) {
  return io::ReadReferenceModel(flag, "--reference", is_table1);
}

namespace {

// "auto" (nullopt) or an integer >= 0, the value of `name` (--modes, --delay-samples).
std::optional<int> AutoOrCount(const std::string& flag, const std::string& name) {
  if (flag == "auto") return std::nullopt;
  try {
    size_t pos = 0;
    const int n = std::stoi(flag, &pos);
    if (pos != flag.size() || n < 0) throw std::invalid_argument("");
    return n;
  } catch (const std::exception&) {
    throw InputError(name + " '" + flag + "': expected 'auto' or an integer >= 0");
  }
}

}  // namespace

void ResolveModesFlag(const std::string& flag, fit::FitOptions* o) {
  const std::optional<int> n = AutoOrCount(flag, "--modes");
  o->auto_modes = !n;
  if (n) o->num_modes = *n;
}

void AddFitFlags(CLI::App* cmd, FitFlags* f) {
  cmd->add_option("--modes", f->modes, "resonance/antiresonance sections (0: rigid body) or 'auto' (0..--max-modes, by BIC)")->capture_default_str();
  cmd->add_option("--max-modes", f->o.max_modes, "largest order --modes auto tries, <= 8")->capture_default_str();
  cmd->add_option("--delay-samples", f->delay, "input delay [samples] or 'auto' (searched from the phase of H / G_rigid)")->capture_default_str();
  cmd->add_option("--max-delay", f->o.max_auto_delay, "largest delay --delay-samples auto tries [samples]")->capture_default_str();
  cmd->add_flag("--allow-short", f->o.allow_few_averages, "fit a response of fewer than 3 Welch segments anyway (judged poor)");
  cmd->add_option("--min-input-power", f->o.band.min_input_power_ratio,
                  "bins used only where the input PSD is at least this fraction of its 99th percentile")->capture_default_str();
  cmd->add_option("--min-coherence", f->o.band.min_coherence, "bins with lower coherence are not used")->capture_default_str();
  cmd->add_option("--noise-coherence-sigmas", f->o.band.noise_coherence_sigmas,
                  "leave out the region at the top of the band whose coherence is within this many std of what "
                  "noise alone gives (bins near Nyquist that are noise; 0: off)")->capture_default_str();
}

void FitFlags::Resolve(double fmin_hz, double fmax_hz) {
  ResolveModesFlag(modes, &o);
  ResolveDelayFlag(delay, &o);
  o.band.fmin_hz = fmin_hz;
  o.band.fmax_hz = fmax_hz;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
}

// The library names option fields; the CLI shows its flags (WithFlags).
std::string FitReport(const fit::FitResult& r) { return io::WithFlags(analysis::FitReport(r)); }

void ResolveDelayFlag(const std::string& flag, fit::FitOptions* o) {
  const std::optional<int> d = AutoOrCount(flag, "--delay-samples");
  o->auto_delay = !d;
  if (d) o->delay_samples = *d;
}

void AddFrictionFlag(CLI::App* cmd, std::string* flag) {
  cmd->add_option("--friction", *flag,
                  "Coulomb friction: auto (fitted when the log shows it), coulomb (always fitted) or none (the linear "
                  "fit; friction only detected); needs one time-domain log")
      ->capture_default_str();
}

}  // namespace zwidth::flags
