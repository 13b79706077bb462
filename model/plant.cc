#include "model/plant.h"

#include <cmath>
#include <sstream>

#include "model/error.h"

namespace zwidth::model {
namespace {

bool CheckPositive(const char* name, double value, std::string* why) {
  if (std::isfinite(value) && value > 0.0) return true;
  if (why != nullptr) {
    std::ostringstream os;
    os.precision(17);
    os << name << " = " << value << ": must be finite and > 0";
    *why = os.str();
  }
  return false;
}

}  // namespace

bool Plant::IsValid(std::string* why) const {
  if (!CheckPositive("m", m, why) || !CheckPositive("b", b, why)) return false;
  for (size_t i = 0; i < modes.size(); ++i) {
    const std::string p = "modes[" + std::to_string(i) + "].";
    const Mode& md = modes[i];
    if (!CheckPositive((p + "omega").c_str(), md.omega, why) ||
        !CheckPositive((p + "c").c_str(), md.c, why) ||
        !CheckPositive((p + "v").c_str(), md.v, why) ||
        !CheckPositive((p + "d").c_str(), md.d, why)) {
      return false;
    }
  }
  if (delay_samples < 0) {
    if (why != nullptr) {
      *why = "delay_samples = " + std::to_string(delay_samples) + ": must be >= 0";
    }
    return false;
  }
  return true;
}

void Plant::Validate() const {
  std::string why;
  if (!IsValid(&why)) throw InputError("invalid model: " + why);
}

Plant PhantomTable1() {
  Plant p;
  p.name = "PHANToM 1.0 phi axis, Table I";
  p.m = 1.168e-3;
  p.b = 0.00584;
  p.modes = {{479.166, 83.0, 417.612, 80.0}, {1159.31, 352.0, 546.626, 90.0}};
  return p;
}

std::complex<double> ContinuousResponse(const Plant& plant, double omega_rad_s) {
  const std::complex<double> s(0.0, omega_rad_s);
  std::complex<double> g = 1.0 / (plant.m * s * s + plant.b * s);
  for (const Mode& md : plant.modes) {
    const double w2 = md.omega * md.omega;
    const double v2 = md.v * md.v;
    g *= (w2 * (s * s + md.d * s + v2)) / (v2 * (s * s + md.c * s + w2));
  }
  return g;
}

}  // namespace zwidth::model
