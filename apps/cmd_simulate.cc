#include <algorithm>
#include <cstdio>

#include "apps/common.h"
#include "io/printable.h"
#include "apps/friction_flags.h"
#include "io/atomic_file.h"
#include "io/log.h"
#include "io/model_json.h"
#include "model/error.h"
#include "model/nonlinear_simulate.h"
#include "model/simulate.h"
#include "model/units.h"

namespace zwidth::app {
namespace {
// Fewer encoder steps than this over the whole output: warned about.
constexpr double kFewEncoderSteps = 50.0;

}  // namespace

void AddSimulateCommand(CLI::App& app) {
  struct Flags {
    std::string model, out, units;  // units "": the model's
    model::SimulateOptions o;
    FrictionFlags friction;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("simulate", "simulate a white-noise torque log from a model");
  cmd->add_option("--model", f->model, "model JSON")->required();
  cmd->add_option("-o,--output", f->out, "log to write (.h5 or .csv)")->required();
  cmd->add_option("--seconds", f->o.seconds, "length [s]")->capture_default_str();
  cmd->add_option("--rate", f->o.sample_rate_hz, "sample rate [Hz]")->capture_default_str();
  cmd->add_option("--units", f->units,
                  "the model's axis: rotary (N m, rad) | linear (N, m); default and must agree: the model file's")
      ->default_str("the model's");
  cmd->add_option("--torque-rms", f->o.torque_rms, "torque RMS [N m] (force [N] for a linear model)")->capture_default_str();
  cmd->add_option("--bandwidth-hz", f->o.bandwidth_hz, "torque band limit [Hz]")->capture_default_str();
  cmd->add_option("--encoder-step", f->o.encoder_step_rad, "rad (m: linear) per encoder count (0: none)")->capture_default_str();
  cmd->add_option("--noise-std", f->o.noise_std_rad, "sensor noise std [rad] ([m]: linear)")->capture_default_str();
  cmd->add_option("--delay-samples", f->o.delay_samples, "extra input delay [samples]")->capture_default_str();
  AddSeedOption(cmd, &f->o.seed, "random seed");
  AddFrictionFlags(cmd, &f->friction);
  cmd->callback([f] {
    io::CheckOutputFolder(f->out, {f->model});
    io::CheckOutputKind(f->out, "a log (CSV, or HDF5 for .h5)", io::kCsvOrHdf5Extensions);
    // The rules of the options (rate, band, length, delay) are SimulateOptions::IsValid's.
    std::string why;
    if (!f->o.IsValid(&why)) throw InputError(WithFlags(why));
    const io::ModelFile mf = io::ReadModelJsonFor(f->model, "simulate --model");
    // The log is in the model's units; --units names them and must agree (a
    // linear model's force cannot be written as torque).
    if (!f->units.empty() && LinearUnits(f->units) != mf.linear) {
      throw InputError("--units " + f->units + ", but " + io::Printable(f->model) + " is a " +
                       model::Units(mf.linear).word + " model (its \"units\"); drop --units (the log takes the "
                       "model's) or simulate a " + model::Units(!mf.linear).word + " model");
    }
    const model::UnitLabels& units = model::Units(mf.linear);
    const model::Friction friction = ResolveFriction(f->friction, mf);
    const model::Actuator actuator = ResolveActuator(f->friction);
    const bool nonlinear = !friction.IsZero() || !actuator.IsZero();
    const model::SimulatedLog log = nonlinear ? model::SimulateNonlinearLog(mf.plant, f->o, friction, actuator)
                                              : model::SimulateLog(mf.plant, f->o);
    io::WriteLog(f->out, log.sample_rate_hz, log.torque, log.position, mf.linear);
    // A device heavier or stiffer than the defaults (PHANToM values) barely
    // moves: an output of a few encoder counts identifies nothing.
    if (f->o.encoder_step_rad > 0.0 && !log.position.empty()) {
      const auto [lo, hi] = std::minmax_element(log.position.begin(), log.position.end());
      const double steps = (*hi - *lo) / f->o.encoder_step_rad;
      if (steps < kFewEncoderSteps) {
        std::fprintf(stderr,
                     "warning: the output spans only %.0f encoder steps (%g %s, --encoder-step %g): quantisation "
                     "dominates it and a fit will be poor; raise --torque-rms (now %g %s) or lower --encoder-step\n",
                     steps, *hi - *lo, units.position, f->o.encoder_step_rad, f->o.torque_rms, units.input);
      }
    }
    if (nonlinear) {
      std::fprintf(stderr, "friction: Coulomb %g / %g, offset %g, breakaway %g / %g%s; actuator: saturation %g, "
                   "DAC step %g (0: none)\n", friction.coulomb_pos, friction.coulomb_neg, friction.offset,
                   friction.StaticPos(), friction.StaticNeg(),
                   (mf.friction && friction.coulomb_pos == mf.friction->coulomb_pos &&
                    friction.coulomb_neg == mf.friction->coulomb_neg) ? " (the model's)" : "",
                   actuator.saturation, actuator.dac_step);
    }
    std::fprintf(stderr, "wrote %zu samples at %g Hz to %s\n", log.torque.size(),
                 log.sample_rate_hz, io::Printable(f->out).c_str());
  });
}

}  // namespace zwidth::app
