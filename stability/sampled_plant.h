// The sampled plant of one (model, period, hand): everything of the Z-width
// computation that does not depend on the loop delay or the velocity filter,
// built once and shared by every delay, the comparison, the boundary rows, the
// uncertainty and the figures.
//
//   - the exact ZOH state-space response G_d(z) (balanced, Hessenberg form;
//     model/state_space.h), without the plant's own input delay;
//   - its pole-residue form (model/zoh_modal.h) where that is checked exact
//     (no hand; distinct underdamped modes): in double, or where crowded modes
//     make its terms cancel past double, in binary128 (see the constructor);
//   - G_d = N(z)/D(z): D from the exactly known discrete poles e^{pT}, N by
//     interpolation at the rotated roots of unity;
//   - the theta points around every resonance and antiresonance that the
//     boundary grid needs (stability/zwidth.h).
//
// Copying is cheap (a shared, immutable body), so a ZWidth keeps its own copy.
#pragma once

#include <complex>
#include <limits>
#include <memory>
#include <vector>

#include "model/plant.h"
#include "model/state_space.h"
#include "model/zoh_modal.h"
#include "stability/loop_options.h"

namespace zwidth::stability {
// Each patch: the damped frequency sqrt(w^2 - c^2/4) T +- k h, h = max(c T / 16,
// 1e-9) rad, k = -kModePatchHalfWidth..kModePatchHalfWidth, inside (pi 1e-7, pi (1 - 1e-9)).
constexpr int kModePatchHalfWidth = 320;

// How well double precision places the sampled plant's poles, per (model,
// period, hand): the conditioning the closed-loop eigenvalue test rests on
// (issue 31, must-have 3). Poles: the eigenvalues z_i of the discrete A
// (balanced, as the closed-loop test balances its matrix).
struct PoleConditioning {
  // min_{i != j} |z_i - z_j| / max_{i, j} |z_i - z_j| over the poles (a
  // conjugate pair counts as two): ~0.01 for a few separated modes, 1e-5 and
  // below for lightly damped modes within 1 % of each other.
  double relative_separation = std::numeric_limits<double>::quiet_NaN();
  // max_i kappa_i, kappa_i = |x_i| |y_i| / |y_i^H x_i| (right and left
  // eigenvectors): how much a perturbation of A moves z_i.
  double eigenvalue_condition = std::numeric_limits<double>::quiet_NaN();
  // max_i eps |A|_F kappa_i / (1 - |z_i|) over the poles inside the circle
  // (the integrator at z = 1 aside): LAPACK's error bound of a computed
  // eigenvalue (EPS * ABNRM / RCONDE, the LAPACK Users' Guide section 4.8)
  // relative to that pole's distance to the unit circle. The eigenvalue
  // test's analogue of denominator_pole_shift.
  double eigenvalue_shift = std::numeric_limits<double>::quiet_NaN();
};

// The warning rule: the eigenvalue test's answers near a boundary rest on the
// double-precision eigenvalues when eigenvalue_shift exceeds this: the
// relative neighbourhood of a boundary outside which the answers are stated
// exact (the 1e-6 offsets at which ZWidth verifies each interval end), so a
// pole's rounding error can then reach into it.
constexpr double kEigenvalueShiftWarning = 1e-6;

class SampledPlant {
 public:
  // Throws InputError for an invalid plant, period or hand.
  SampledPlant(const model::Plant& plant, double period_s, const Hand& hand = {});

  const model::Plant& plant() const { return d_->plant; }
  double period_s() const { return d_->period_s; }
  const Hand& hand() const { return d_->hand; }
  // Without a hand stiffness G has its integrator pole at z = 1.
  bool has_integrator() const { return d_->has_integrator; }

  // G_d(z) without any delay: the pole-residue form where it is checked
  // exact (in double, O(n); else built in binary128 and summed in
  // double-double, O(n) at ~12 double-double operations per term),
  // else the Hessenberg solve (O(n^2)).
  std::complex<double> Gd(std::complex<double> z) const;
  // Which form Gd uses.
  bool gd_pole_residue() const { return d_->use_modal; }
  bool gd_binary128() const { return d_->quad != nullptr; }
  // G_d(z) by the Hessenberg solve alone, without any delay.
  std::complex<double> GdStateSpace(std::complex<double> z) const { return d_->response.AtZ(z); }
  // G_d(e^{j theta}) e^{-j theta delay} with the plant's own input delay: the
  // model's sampled frequency response (theta = omega T in rad/sample).
  std::complex<double> AtTheta(double theta) const;
  // N(z) and monic D(z) of G_d = N/D, z^0 first; D1 = D/(z - 1) when
  // has_integrator(), else D.
  const std::vector<double>& numerator() const { return d_->num; }
  const std::vector<double>& denominator() const { return d_->den; }
  const std::vector<double>& denominator_without_integrator() const { return d_->den1; }
  // Theta points in (0, pi) dense around every resonance and antiresonance
  // (and the hand's poles), unsorted.
  const std::vector<double>& mode_patch_theta() const { return d_->patch_theta; }
  // The discrete state space (balanced ZOH, no delay) and the index of the
  // integrator's (position) state in it, -1 without an integrator.
  const model::StateSpace& discrete() const { return d_->discrete; }
  int position_state() const { return d_->position_state; }
  // How far rounding D(z)'s coefficients to double moves its exactly known
  // roots e^{pT} (RootDisplacementBound, stability/closed_loop.h), relative to
  // each one's distance to the unit circle: the largest ratio (the integrator
  // at z = 1 aside). ~1e-12 for a few separated modes; 1 and more for many
  // lightly damped modes crowded together, where no polynomial test holds.
  double denominator_pole_shift() const { return d_->denominator_pole_shift; }
  // The poles' conditioning (computed once, O(n^3)).
  const PoleConditioning& conditioning() const { return d_->conditioning; }
  // G_d(-1).
  std::complex<double> gd_at_minus_one() const { return d_->g_minus_one; }

 private:
  struct Binary128Modal;  // the pole-residue form in binary128 (sampled_plant.cc)
  // That form where it holds to 1e-12 of |G_d| (sampled_plant.cc); nullptr elsewhere.
  static std::shared_ptr<const Binary128Modal> Binary128Form(const model::Plant& plant, double T,
                                                             const std::vector<double>& patch_theta);
  struct Data {
    model::Plant plant;
    double period_s = 0.0;
    Hand hand;
    bool has_integrator = true;
    model::DiscreteResponse response;
    model::ZohModalForm<double> modal;
    bool use_modal = false;
    std::shared_ptr<const Binary128Modal> quad;  // set where Gd uses binary128
    std::vector<double> num, den, den1;
    std::vector<double> patch_theta;
    std::complex<double> g_minus_one;
    model::StateSpace discrete;
    int position_state = -1;
    double denominator_pole_shift = 0.0;
    PoleConditioning conditioning;
    explicit Data(const model::StateSpace& s) : response(s) {}
  };
  std::shared_ptr<const Data> d_;
};

}  // namespace zwidth::stability
