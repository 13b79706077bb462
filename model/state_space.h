// State-space realisations of the plant and its exact zero-order-hold (ZOH)
// discretisation.
//
// The continuous realisation is a cascade, input -> section 1 -> ... ->
// section N -> rigid body -> position, in which every entry is of the order of
// a natural frequency (no expanded polynomial coefficients, which lose digits
// at this order). Section i with states (p, q):
//   p' = w q,   q' = -w p - c q + u_i,
//   y_i = (w^2/v^2) [ (v^2 - w^2)/w p + (d - c) q + u_i ],
// which realises (w^2/v^2)(s^2 + d s + v^2)/(s^2 + c s + w^2) exactly.
// Rigid body with states (m theta, m theta'): (m theta')' = u - (b/m)(m theta'),
// position = (m theta)/m.
#pragma once

#include <complex>
#include <vector>

#include <Eigen/Core>

#include "model/plant.h"

namespace zwidth::model {

struct StateSpace {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C;
  double D = 0.0;
  // 0 for a continuous system; the sample period [s] for a discrete one.
  double period_s = 0.0;
  // Input delay of a discrete system [samples]; not part of A (see Response).
  int delay_samples = 0;
};

// The continuous realisation described above. Precondition: plant valid.
StateSpace ContinuousStateSpace(const Plant& plant);

// Exact ZOH discretisation at period T: Ad = e^{AT}, Bd = int_0^T e^{As} ds B,
// from the matrix exponential of the augmented matrix [[A, B], [0, 0]] T
// (Van Loan). The plant's delay_samples is carried along. Throws InputError for
// a period that is not finite and positive.
StateSpace DiscretizeZoh(const Plant& plant, double period_s);
// The same for any continuous state space (delay_samples 0): e.g. the plant
// with the hand (stability/hand.h) or the stuck plant of
// model/nonlinear_simulate.h.
StateSpace DiscretizeZoh(const StateSpace& continuous, double period_s);

// The same system with the input delay realised as extra states (a shift
// register), so that A alone describes the whole sampled plant.
StateSpace WithDelayStates(const StateSpace& discrete);

// Frequency response of a discrete state-space system,
//   G_d(e^{j theta}) e^{-j theta delay} = (C (zI - A)^{-1} B + D) z^{-delay}.
// A is reduced once to Hessenberg form, so each evaluation costs O(n^2).
class DiscreteResponse {
 public:
  explicit DiscreteResponse(const StateSpace& discrete);
  // theta = omega T in rad/sample; includes the delay.
  std::complex<double> AtTheta(double theta) const;
  // At an arbitrary point z, without the delay factor.
  std::complex<double> AtZ(std::complex<double> z) const;
  int delay_samples() const { return delay_samples_; }

 private:
  Eigen::MatrixXd H_;       // upper Hessenberg, A = Q H Q^T
  Eigen::VectorXd QtB_;     // Q^T B
  Eigen::RowVectorXd CQ_;   // C Q
  double D_ = 0.0;
  int delay_samples_ = 0;
};

// Sampled simulation: x_{k+1} = A x_k + B u_{k-delay}, y_k = C x_k + D u_{k-delay},
// from rest. With a ZOH plant this is exactly the continuous plant driven by
// the input held over each period and sampled at the start of each period.
std::vector<double> SimulateDiscrete(const StateSpace& discrete,
                                     const std::vector<double>& input);

}  // namespace zwidth::model
