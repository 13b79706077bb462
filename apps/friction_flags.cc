#include "apps/friction_flags.h"

#include <cmath>
#include <cstdio>

#include "apps/common.h"
#include "model/error.h"

namespace zwidth::app {
namespace {


// A given level: finite, >= 0, at most 1e12.
double Level(const char* flag, double v) {
  if (!(std::isfinite(v) && v >= 0.0 && v <= 1e12)) {
    throw InputError(std::string(flag) + " " + Num(v) + ": must be a finite torque >= 0 (N m, or N for a linear "
                     "model) and at most 1e12");
  }
  return v;
}

bool Given(const CLI::Option* o) { return o != nullptr && o->count() > 0; }

}  // namespace

void AddFrictionFlags(CLI::App* cmd, FrictionFlags* f) {
  f->coulomb_opt = cmd->add_option("--coulomb", f->coulomb, "Coulomb friction level at the motor, both directions [N m]");
  f->coulomb_pos_opt = cmd->add_option("--coulomb-pos", f->coulomb_pos, "Coulomb level opposing positive velocity [N m]");
  f->coulomb_neg_opt = cmd->add_option("--coulomb-neg", f->coulomb_neg, "Coulomb level opposing negative velocity (a magnitude) [N m]");
  f->offset_opt =
      cmd->add_option("--friction-offset", f->offset, "constant torque offset (gravity, amplifier bias) [N m]");
  f->breakaway_opt = cmd->add_option("--breakaway", f->breakaway, "static (breakaway) level, both directions, >= the Coulomb level [N m]");
  cmd->add_flag("--no-model-friction", f->no_model_friction, "ignore the model file's \"friction\"");
  cmd->add_option("--torque-saturation", f->saturation, "actuator torque limit |u| [N m] (0: none)")
      ->capture_default_str();
  cmd->add_option("--dac-step", f->dac_step, "actuator command step [N m] (0: none)")->capture_default_str();
}

model::Friction ResolveFriction(const FrictionFlags& f, const io::ModelFile& mf) {
  const bool any = Given(f.coulomb_opt) || Given(f.coulomb_pos_opt) || Given(f.coulomb_neg_opt) || Given(f.breakaway_opt) ||
                   Given(f.offset_opt);
  if (!any) return (mf.friction && !f.no_model_friction) ? *mf.friction : model::Friction{};
  if (Given(f.coulomb_opt) && (Given(f.coulomb_pos_opt) || Given(f.coulomb_neg_opt))) {
    throw InputError("give --coulomb (both directions) or --coulomb-pos/--coulomb-neg, not both");
  }
  model::Friction out;
  if (Given(f.coulomb_opt)) out.coulomb_pos = out.coulomb_neg = Level("--coulomb", f.coulomb);
  if (Given(f.coulomb_pos_opt)) out.coulomb_pos = Level("--coulomb-pos", f.coulomb_pos);
  if (Given(f.coulomb_neg_opt)) out.coulomb_neg = Level("--coulomb-neg", f.coulomb_neg);
  if (!(std::isfinite(f.offset) && std::abs(f.offset) <= 1e12)) {
    throw InputError("--friction-offset " + Num(f.offset) + ": must be a finite torque, at most 1e12 in size");
  }
  out.offset = f.offset;
  if (Given(f.breakaway_opt)) {
    const double s = Level("--breakaway", f.breakaway);
    if (s < std::max(out.coulomb_pos, out.coulomb_neg)) {
      throw InputError("--breakaway " + Num(s) + " is below the Coulomb level " +
                       Num(std::max(out.coulomb_pos, out.coulomb_neg)) +
                       ": the static level is at least the sliding one; raise --breakaway or leave it out");
    }
    out.breakaway_pos = out.breakaway_neg = s;
  }
  return out;
}

model::Actuator ResolveActuator(const FrictionFlags& f) {
  return model::Actuator{Level("--torque-saturation", f.saturation), Level("--dac-step", f.dac_step)};
}

}  // namespace zwidth::app
