// The fit's option checks and result wording: what the zwidth executable
// uses of zwidth_fit without the fit itself (kept apart from fit.cc so that
// linking them does not pull in Ceres; the fit comes from a plugin, fit/fit_api.h).
#include <cmath>
#include <cstdio>
#include <locale>
#include <sstream>
#include <string>

#include "fit/fit.h"
#include "fit/friction_fit.h"

namespace zwidth::fit {

bool FitOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (num_modes < 0 || num_modes > 20) return bad("FitOptions::num_modes must be in [0, 20]");
  // A model file holds a delay up to model::kMaxDelaySamples: 100000 was fitted and written, then refused.
  if (delay_samples < 0 || delay_samples > model::kMaxDelaySamples) {
    return bad("FitOptions::delay_samples must be in [0, " + std::to_string(model::kMaxDelaySamples) + "]");
  }
  if (max_auto_delay < 0 || max_auto_delay > 1000) return bad("FitOptions::max_auto_delay must be in [0, 1000]");
  if (!(min_damping_ratio > 0 && min_damping_ratio < max_pole_damping_ratio)) return bad("FitOptions::min_damping_ratio must be in (0, FitOptions::max_pole_damping_ratio)");
  if (!(max_pole_damping_ratio < 1.0)) return bad("FitOptions::max_pole_damping_ratio must be < 1");
  if (!(max_zero_damping_ratio > min_damping_ratio)) return bad("FitOptions::max_zero_damping_ratio must be > FitOptions::min_damping_ratio");
  if (!(max_frequency_fraction > 0 && max_frequency_fraction < 1)) return bad("FitOptions::max_frequency_fraction must be in (0, 1)");
  if (!(relative_std_floor >= 0)) return bad("FitOptions::relative_std_floor must be >= 0");
  if (!(local_relative_std_floor >= 0)) return bad("FitOptions::local_relative_std_floor must be >= 0");
  if (max_iterations < 1) return bad("FitOptions::max_iterations must be >= 1");
  if (!(function_tolerance > 0)) return bad("FitOptions::function_tolerance must be > 0");
  if (max_starts < 1) return bad("FitOptions::max_starts must be >= 1");
  if (max_modes < 0 || max_modes > 8) return bad("FitOptions::max_modes must be in [0, 8]");
  if (min_averages < 1) return bad("FitOptions::min_averages must be >= 1");
  if (max_converged_starts < 1) return bad("FitOptions::max_converged_starts must be >= 1");
  if (!(runner_up_cost_ratio >= 1.0)) return bad("FitOptions::runner_up_cost_ratio must be >= 1");
  if (std::string w; !band.IsValid(&w)) return bad(w);
  if (!auto_modes && init && static_cast<int>(init->modes.size()) != num_modes) {
    return bad("FitOptions::init has " + std::to_string(init->modes.size()) + " modes but FitOptions::num_modes is " + std::to_string(num_modes));
  }
  return true;
}

std::string ToString(FitStatus s) {
  switch (s) {
    case FitStatus::kNotRun: return "not run";
    case FitStatus::kConverged: return "converged";
    case FitStatus::kNoConvergence: return "no convergence";
  }
  return "?";
}

std::string FitResult::BriefReport() const {
  std::ostringstream os;
  os.imbue(std::locale::classic());  // '.' decimals whatever std::locale::global says
  os << "fit " << ToString(status) << ": chi2/dof " << chi2_per_dof << ", fit " << nrmse_fit_percent
     << "% (NRMSE of H; unweighted, so a large misfit where |H| is small hardly shows), worst misfit at "
     << worst_misfit_hz << " Hz, " << starts_tried << " starts, " << iterations << " iterations";
  return os.str();
}

namespace {
std::string FrictionNum(const char* fmt, double a) {
  char s[200];
  std::snprintf(s, sizeof s, fmt, a);
  return s;
}
}  // namespace

// The friction fit's names and option checks (fit/friction_fit.h), here for
// the same reason.
std::string ToString(FrictionModel f) {
  switch (f) {
    case FrictionModel::kNone: return "none";
    case FrictionModel::kAuto: return "auto";
    case FrictionModel::kCoulomb: return "coulomb";
  }
  return "?";
}

bool FrictionModelFromString(const std::string& s, FrictionModel* f) {
  for (FrictionModel c : {FrictionModel::kNone, FrictionModel::kAuto, FrictionModel::kCoulomb}) {
    if (s == ToString(c)) { *f = c; return true; }
  }
  return false;
}

std::string ToString(FrictionTopology t) {
  switch (t) {
    case FrictionTopology::kRigidBody: return "rigid body";
    case FrictionTopology::kCollocated: return "collocated";
  }
  return "?";
}

bool FrictionTopologyFromString(const std::string& s, FrictionTopology* t) {
  for (FrictionTopology c : {FrictionTopology::kRigidBody, FrictionTopology::kCollocated}) {
    if (s == ToString(c)) { *t = c; return true; }
  }
  return false;
}

std::string ToString(FrictionFitStatus s) {
  switch (s) {
    case FrictionFitStatus::kNotRun: return "not run";
    case FrictionFitStatus::kFitted: return "fitted";
    case FrictionFitStatus::kNotDetected: return "not detected";
    case FrictionFitStatus::kNotIdentified: return "not identified";
  }
  return "?";
}

bool FrictionFitOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) { if (why) *why = m; return false; };
  if (!(cutoff_hz >= 0.0) || !std::isfinite(cutoff_hz)) return fail(FrictionNum("FrictionFitOptions::cutoff_hz = %g: must be 0 (automatic) or > 0 [Hz]", cutoff_hz));
  if (!(min_speed_fraction >= 0.0 && min_speed_fraction < 1.0)) return fail(FrictionNum("FrictionFitOptions::min_speed_fraction = %g: must be in [0, 1)", min_speed_fraction));
  if (iterations < 1 || iterations > 20) return fail(FrictionNum("FrictionFitOptions::iterations = %.0f: must be in [1, 20]", iterations));
  if (!(detection_z > 0.0) || !std::isfinite(detection_z)) return fail(FrictionNum("FrictionFitOptions::detection_z = %g: must be > 0", detection_z));
  return true;
}

}  // namespace zwidth::fit
