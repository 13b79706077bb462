#include <cstdio>

#include "apps/common.h"
#include "io/atomic_file.h"
#include "io/log.h"
#include "io/model_json.h"
#include "model/error.h"
#include "model/simulate.h"

namespace zwidth::app {

void AddSimulateCommand(CLI::App& app) {
  struct Flags {
    std::string model, out;
    model::SimulateOptions o;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = app.add_subcommand("simulate", "simulate a white-noise torque log from a model");
  cmd->add_option("--model", f->model, "model JSON")->required();
  cmd->add_option("-o,--output", f->out, "log to write (.h5 or .csv)")->required();
  cmd->add_option("--seconds", f->o.seconds, "length [s]")->capture_default_str();
  cmd->add_option("--rate", f->o.sample_rate_hz, "sample rate [Hz]")->capture_default_str();
  cmd->add_option("--torque-rms", f->o.torque_rms, "torque RMS [N m]")->capture_default_str();
  cmd->add_option("--bandwidth-hz", f->o.bandwidth_hz, "torque band limit [Hz]")->capture_default_str();
  cmd->add_option("--encoder-step", f->o.encoder_step_rad, "rad per encoder count (0: none)")->capture_default_str();
  cmd->add_option("--noise-std", f->o.noise_std_rad, "sensor noise std [rad]")->capture_default_str();
  cmd->add_option("--delay-samples", f->o.delay_samples, "extra input delay [samples]")->capture_default_str();
  cmd->add_option("--seed", f->o.seed, "random seed")->capture_default_str();
  cmd->callback([f] {
    io::CheckOutputFolder(f->out, {f->model});
    // At most kMaxSimulateSamples (1e8, 28 h at 1 kHz: 1.6 GB of samples in memory).
    constexpr double kMaxSimulateSamples = 1e8;
    const double samples = f->o.seconds * f->o.sample_rate_hz;
    if (!(samples <= kMaxSimulateSamples)) {
      throw InputError("--seconds x --rate = " + std::to_string(samples) + " samples, more than " +
                       "simulate writes (1e8); shorten --seconds or lower --rate");
    }
    if (f->o.delay_samples > io::kMaxDelaySamples) {  // the model's own plus this one may not wrap
      throw InputError("--delay-samples " + std::to_string(f->o.delay_samples) + " is more than " +
                       std::to_string(io::kMaxDelaySamples));
    }
    const io::ModelFile mf = io::ReadModelJson(f->model);
    const model::SimulatedLog log = model::SimulateLog(mf.plant, f->o);
    io::WriteLog(f->out, log.sample_rate_hz, log.torque, log.position);
    std::fprintf(stderr, "wrote %zu samples at %g Hz to %s\n", log.torque.size(),
                 log.sample_rate_hz, f->out.c_str());
  });
}

}  // namespace zwidth::app
