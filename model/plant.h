// The plant of eq. (1), generalised to N resonance/antiresonance sections:
//
//   G(s) = 1/(m s^2 + b s) * prod_i  w_i^2 (s^2 + d_i s + v_i^2)
//                                   / (v_i^2 (s^2 + c_i s + w_i^2))
//
// Each section has unit DC gain. N = 0 is the rigid body alone. An optional
// integer input delay z^-delay_samples applies to the sampled model only.
#pragma once

#include <complex>
#include <string>
#include <vector>

namespace zwidth::model {

// The largest input delay [samples] zwidth takes, a model's or a loop's (a delay
// of 10^6 samples makes the sampled loop a polynomial of that degree).
inline constexpr int kMaxDelaySamples = 1000;

// One resonance/antiresonance section of eq. (1). SI units, rad/s.
struct Mode {
  double omega = 0.0;  // pole-pair natural frequency w_i [rad/s], > 0
  double c = 0.0;      // pole-pair damping coefficient c_i = 2 zeta w [rad/s], > 0
  double v = 0.0;      // zero-pair natural frequency v_i [rad/s], > 0
  double d = 0.0;      // zero-pair damping coefficient d_i [rad/s], > 0
};

struct Plant {
  double m = 0.0;            // rigid-body inertia [kg m^2], > 0
  double b = 0.0;            // rigid-body viscous damping [N m s/rad], > 0
  std::vector<Mode> modes;   // 0..any resonance/antiresonance sections
  int delay_samples = 0;     // input delay of the sampled model [samples], in [0, kMaxDelaySamples]
  std::string name;          // free text, optional

  int num_states() const { return 2 + 2 * static_cast<int>(modes.size()); }

  // True when every parameter is finite and positive and the delay is >= 0.
  // Otherwise *why names the parameter (e.g. "modes[1].c = -3: must be > 0").
  bool IsValid(std::string* why) const;
  // Throws InputError with IsValid's message.
  void Validate() const;
};

// The paper's Table I / appendix model (PHANToM 1.0, phi axis).
Plant PhantomTable1();

// G(jw) from the factored formula, w in rad/s. w = 0 gives an infinite value
// (the integrator).
std::complex<double> ContinuousResponse(const Plant& plant, double omega_rad_s);

}  // namespace zwidth::model
