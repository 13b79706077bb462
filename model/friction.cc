#include "model/friction.h"

#include <cmath>
#include <sstream>

#include "model/error.h"

namespace zwidth::model {
namespace {

bool Check(const char* name, double v, bool nonnegative, std::string* why) {
  if (std::isfinite(v) && std::abs(v) <= 1e12 && (!nonnegative || v >= 0.0)) return true;
  if (why != nullptr) {
    std::ostringstream os;
    os.precision(17);
    os << name << " = " << v << ": must be finite" << (nonnegative ? ", >= 0" : "") << " and at most 1e12 in size";
    *why = os.str();
  }
  return false;
}

bool CheckBreakaway(const char* name, double breakaway, double coulomb, std::string* why) {
  if (breakaway == 0.0 || breakaway >= coulomb) return true;
  if (why != nullptr) {
    std::ostringstream os;
    os.precision(17);
    os << name << " = " << breakaway << ": a breakaway level must be 0 (= the Coulomb level) or >= the Coulomb level "
       << coulomb;
    *why = os.str();
  }
  return false;
}

}  // namespace

bool Friction::IsValid(std::string* why) const {
  return Check("coulomb_pos", coulomb_pos, true, why) && Check("coulomb_neg", coulomb_neg, true, why) &&
         Check("offset", offset, false, why) && Check("breakaway_pos", breakaway_pos, true, why) &&
         Check("breakaway_neg", breakaway_neg, true, why) &&
         CheckBreakaway("breakaway_pos", breakaway_pos, coulomb_pos, why) &&
         CheckBreakaway("breakaway_neg", breakaway_neg, coulomb_neg, why);
}

void Friction::Validate() const {
  std::string why;
  if (!IsValid(&why)) throw InputError("friction: " + why);
}

bool Actuator::IsValid(std::string* why) const {
  return Check("saturation", saturation, true, why) && Check("dac_step", dac_step, true, why);
}

double Actuator::Apply(double u) const {
  if (dac_step > 0.0) u = dac_step * std::nearbyint(u / dac_step);
  if (saturation > 0.0) u = std::fmax(-saturation, std::fmin(saturation, u));
  return u;
}

}  // namespace zwidth::model
