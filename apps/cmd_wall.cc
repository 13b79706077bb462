// zwidth wall: the virtual wall simulated on the nonlinear device (friction,
// encoder, actuator), beside the linear Z-width and the friction prediction.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "apps/common.h"
#include "apps/friction_flags.h"
#include "flags/loop_flags.h"
#include "analysis/friction_amplitude.h"
#include "io/atomic_file.h"
#include "io/model_json.h"
#include "io/provenance.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "stability/friction_prediction.h"
#include "stability/wall_simulation.h"

namespace zwidth::app {
namespace {

void WriteWallTrace(const std::string& path, const stability::WallResult& r, double period_s) {
  io::WriteAtomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError("cannot create '" + tmp + "'");
    std::fputs("t,position,measured,force\n", f);
    for (size_t k = 0; k < r.position.size(); ++k) {
      std::fprintf(f, "%.9g,%.12g,%.12g,%.9g\n", k * period_s, r.position[k], r.measured[k], r.force[k]);
    }
    if (std::fclose(f) != 0) throw InputError("failed writing '" + path + "'");
  });
}

nlohmann::json WallJson(const stability::WallResult& r, const stability::FrictionPrediction& p,
                        const stability::WallOptions& o) {
  return {{"outcome", stability::ToString(r.outcome)},
          {"amplitude", io::NumberOrNull(r.amplitude)},
          {"initial_amplitude", io::NumberOrNull(r.initial_amplitude)},
          {"frequency_hz", io::NumberOrNull(r.frequency_hz)},
          {"last_ratio", io::NumberOrNull(r.last_ratio)},
          {"rest_position", io::NumberOrNull(r.rest_position)},
          {"samples", r.samples},
          {"K", o.stiffness}, {"B", o.damping}, {"delay_samples", o.delay_samples}, {"period_s", o.period_s},
          {"prediction", analysis::FrictionPredictionJson(p)}};
}

void PrintWall(const stability::WallResult& r, const stability::FrictionPrediction& p) {
  switch (r.outcome) {
    case stability::WallOutcome::kLimitCycle:
      std::printf("wall: limit cycle, amplitude %.4g rad at %.4g Hz\n", r.amplitude, r.frequency_hz);
      break;
    case stability::WallOutcome::kDecays:
      std::printf("wall: decays (last amplitude %.3g rad, at %.6g rad)\n", r.amplitude, r.rest_position);
      break;
    case stability::WallOutcome::kGrows:
      std::printf("wall: grows (amplitude %.3g rad after %zu samples, from %.3g)\n", r.amplitude, r.position.size(),
                  r.initial_amplitude);
      break;
    default:
      std::printf("wall: unsettled (amplitude %.3g rad, ratio %.4g between the last eighths): simulate longer with "
                  "--seconds\n", r.amplitude, r.last_ratio);
  }
  std::printf("linear Z-width (friction removed): K_cr = %.6g N m/rad: %s\n", p.K_cr_linear,
              p.verdict == stability::FrictionVerdict::kLinearStable ? "stable for any disturbance"
                                                                    : "outside it, unstable at large amplitude");
  if (p.verdict == stability::FrictionVerdict::kStableBelow) {
    std::printf("friction (describing function): stable below an amplitude of %.4g rad (%.4g Hz, extra damping "
                "%.4g)%s%s\n", p.amplitude, p.frequency_hz, p.extra_damping,
                p.valid ? "" : "; outside the prediction's validity: ", p.invalid_reason.c_str());
  } else if (p.verdict == stability::FrictionVerdict::kUnstable) {
    std::printf("friction: does not stabilise it at any amplitude (%s)\n", p.invalid_reason.c_str());
  }
  if (std::isfinite(p.K_rest_max)) {
    std::printf("encoder rest point (K q <= 2 F_c, Abbott and Okamura 2005): %s, K up to %.4g\n",
                p.rest_point_ok ? "holds" : "fails: the wall can buzz between counts", p.K_rest_max);
  }
}

}  // namespace

void AddWallCommand(CLI::App& app) {
  struct WallFlags {
    std::string model, trace;
    stability::WallOptions o;
    double period = kNotGiven;
    bool json = false;
    LoopFlags loop;
    FrictionFlags friction;
    double encoder_step = kNotGiven;  // else the model's
  };
  auto f = std::make_shared<WallFlags>();
  CLI::App* w = app.add_subcommand("wall", "simulate a virtual wall on the device with friction, encoder, actuator");
  w->add_option("model", f->model, "model JSON")->required();
  w->add_option("--stiffness", f->o.stiffness, "virtual stiffness K [N m/rad]")->required();
  w->add_option("--damping", f->o.damping, "virtual damping B [N m s/rad]")->required();
  w->add_option("--delay", f->o.delay_samples, "loop delay [samples]")->required();
  w->add_option("--period", f->period, "sample period T [s] (default: the model's, else 0.001)");
  w->add_option("--seconds", f->o.seconds, "simulated time [s]")->capture_default_str();
  w->add_option("--initial-position", f->o.initial_position, "start at rest here [rad]")->capture_default_str();
  w->add_option("--encoder-step", f->encoder_step, kEncoderStepHelp);
  w->add_flag("--json", f->json, "print only JSON on standard output");
  w->add_option("-o,--output", f->trace, "trace CSV (t, position, measured, force)");
  AddLoopFlags(w, &f->loop);
  AddFrictionFlags(w, &f->friction);
  w->callback([f] {
    if (!f->trace.empty()) io::CheckOutputFolder(f->trace, {f->model});
    if (!f->trace.empty()) io::CheckOutputKind(f->trace, "a trace CSV", io::kCsvExtensions);
    io::ModelFile mf = io::ReadModelJsonFor(f->model, "wall");  // not const: --period may convert its delay
    f->o.period_s = ResolvePeriod(f->period, &mf);
    const std::vector<stability::LoopOptions> loops = ResolveLoops(f->loop, f->o.period_s);
    if (loops.size() != 1) throw InputError("wall: give at most one --hand (the simulation runs one loop)");
    f->o.loop = loops.front();
    f->o.friction = ResolveFriction(f->friction, mf);
    f->o.actuator = ResolveActuator(f->friction);
    f->o.encoder_step = analysis::EncoderStepOf(mf, Given(f->encoder_step), "--encoder-step");
    std::string why;
    if (!f->o.IsValid(&why)) throw InputError(why);
    const stability::WallResult r = stability::SimulateWall(mf.plant, f->o);
    const stability::FrictionPrediction p =
        stability::PredictFriction(mf.plant, f->o.period_s, f->o.delay_samples, f->o.loop, f->o.stiffness,
                                   f->o.damping, f->o.friction, f->o.encoder_step);
    if (!f->trace.empty()) WriteWallTrace(f->trace, r, f->o.period_s);
    if (f->json) {
      nlohmann::json j = WallJson(r, p, f->o);
      j["provenance"] = io::ProvenanceJson();
      std::cout << j.dump() << std::endl;
    } else {
      PrintWall(r, p);
    }
  });
}

}  // namespace zwidth::app
