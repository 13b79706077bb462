// The haptic loop as devices run it (issue 16): a velocity filter in the
// virtual wall, the user's hand on the device, and the passivity boundary of
// Colgate and Schenkel beside the stability boundary.
//
// Loop (with D = loop delay + the model's own input delay, in samples):
//
//   u = -z^-D (K + B F(z) (1 - z^-1)/T) y,    y = G_h(z) u,
//
// F(z) = (b0 + b1 z^-1 + ... + bn z^-n) / (a0 + a1 z^-1 + ... + am z^-m),
// a0 = 1, the velocity filter (F = 1: the paper's raw backward difference),
// and G_h the exact ZOH sampling of the continuous plant with the hand,
//
//   G_h(s) = G(s) / (1 + G(s) Z_h(s)),   Z_h(s) = M s^2 + B_h s + K_h.
//
// Where the hand is attached: its force acts where the motor torque does (the
// plant input) and it feels the measured coordinate y (position, velocity,
// acceleration). With modes, that treats the hand as collocated with the
// encoder and the motor: the modes stay between the torque and y exactly as
// identified, and the hand does not sit behind a compliant link. M, B_h, K_h
// are in the model's units at that coordinate (kg m^2, N m s/rad, N m/rad for
// a rotary model; kg, N s/m, N/m for a linear one).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "model/plant.h"
#include "model/state_space.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

namespace zwidth::stability {

// First-order low-pass F = (1 - a)/(1 - a z^-1), a = exp(-2 pi f_c T). Throws
// InputError unless 0 < f_c < 1/(2T).
void SetLowPassFilter(double cutoff_hz, double period_s, LoopOptions* loop);

// Parses "b:b0,b1,...;a:a0,a1,..." (a0 must be 1). Throws InputError naming
// the problem. `what` names the source in messages (a flag or a file path).
void ParseFilterCoefficients(const std::string& text, const std::string& what, LoopOptions* loop);

// "M,B,K" in SI; throws InputError (negative or non-finite values, not three numbers).
Hand ParseHand(const std::string& text);

// Continuous realisation of G / (1 + G Z_h) from the plant's (ContinuousStateSpace).
// G is strictly proper of relative degree 2 (C B = 0), so y'' = C A^2 x + g u_p
// with g = C A B; solving u_p = u - M y'' - B_h y' - K_h y for the plant input u_p:
//   u_p = (u - (M C A^2 + B_h C A + K_h C) x) / (1 + M g),
//   A_h = A - B (M C A^2 + B_h C A + K_h C) / (1 + M g),  B_h = B / (1 + M g).
// (g = 1/m times the product of the sections' high-frequency gains, > 0, so
// 1 + M g > 0 for M >= 0.) No polynomial is formed. Precondition: plant valid.
model::StateSpace ContinuousStateSpaceWithHand(const model::Plant& plant, const Hand& hand);

// Exact ZOH of a continuous state space (Van Loan, balanced as DiscretizeZoh).
model::StateSpace DiscretizeZohStateSpace(const model::StateSpace& continuous, double period_s);

// The stable set at one B for several loops (e.g. a range of hands): the
// intersection of their interval sets. Ends keep the frequency of the loop that sets them.
std::vector<KInterval> IntersectIntervals(const std::vector<KInterval>& a, const std::vector<KInterval>& b);

// ---- Passivity (Colgate and Schenkel, 1997, Theorem 1, in their notation):
// the sampled system of a mass m with physical damping b, ZOH, and a discrete
// environment H(z) is passive iff
//   b > (T/2) / (1 - cos(w T)) Re{(1 - e^{-j w T}) H(e^{j w T})},  0 <= w <= pi/T.
// With H = z^-D (K + B F(z)(1 - z^-1)/T) and theta = w T this is, exactly,
//   b > K P(theta) - B R(theta),
//   P = (T/2) sin((2D + 1) theta/2) / sin(theta/2),  R = Re{e^{-j(D+1) theta} F(e^{j theta})}
// (P(0) = (2D + 1) T/2). For D = 0, F = 1: b > K T/2 + |B|. It is affine in K at
// fixed B, so the passive K >= 0 form an interval [K_lo, K_hi] with
//   K_hi = min over P > 0 of (b + B R)/P,   K_lo = max(0, max over P < 0 of (b + B R)/P).
// b is the rigid body's damping of the model (the modes and the hand are not
// part of the condition: it is the device-side physical damping of the theorem).
struct PassivityOptions {
  int min_grid_points = 4096;     // uniform theta grid on [0, pi], >= 64
  int grid_points_per_delay = 64; // extra points per sample of delay (+ filter order), >= 8
  double theta_tolerance = 1e-12; // golden-section refinement of each local minimum [rad], in (0, 1e-3)
  bool IsValid(std::string* why) const;
};

struct PassiveInterval {
  // Largest passive K at this B [N m/rad]; 0 when no K >= 0 is passive.
  double K_hi = std::numeric_limits<double>::quiet_NaN();
  double K_lo = 0.0;  // smallest passive K >= 0 [N m/rad]
  double theta_hi = std::numeric_limits<double>::quiet_NaN();  // where K_hi is set [rad/sample]
  bool passive_set_empty = false;
};

class Passivity {
 public:
  // b_phys: the physical damping [N m s/rad] (> 0); total_delay D >= 0.
  Passivity(double b_phys, double period_s, int total_delay, const LoopOptions& loop,
            const PassivityOptions& options = {});
  PassiveInterval At(double B) const;
  // At(B).K_hi alone: the lower bounds are searched only for one at or above
  // K_hi (which empties the set), not for the largest.
  double KHi(double B) const;
  // The condition's right-hand side K P - B R at theta (for tests and plots).
  double Rhs(double K, double B, double theta) const;

 private:
  void PR(double theta, double* P, double* R) const;
  // min over theta of sign (b + B R)/P where sign P > 0, if below `best`
  // (else `best`); *theta (may be null): where it is set.
  double Smallest(double B, double sign, double best, double* theta) const;
  double b_, T_;
  int D_;
  LoopOptions loop_;
  PassivityOptions options_;
  // The theta grid, P, R and 1/P (0 where P = 0) on it; penalties added to the
  // upper bounds (0 where P > 0, +inf elsewhere) and to minus the lower ones
  // (0 where P < 0, +inf elsewhere); the grid points where P = 0.
  std::vector<double> th_, P_, R_, inv_P_, upper_penalty_, lower_penalty_;
  std::vector<size_t> zero_P_;
  // Bounds of the lines a_i + s_i B over a block's points of one sign of P,
  // and of the steps between neighbours (see the constructor).
  struct LineBounds {
    bool any = false;
    bool edge = false;  // a point here has a neighbour of the other sign (or P = 0)
    double a_min = std::numeric_limits<double>::infinity(), a_max = -std::numeric_limits<double>::infinity();
    double s_min = std::numeric_limits<double>::infinity(), s_max = -std::numeric_limits<double>::infinity();
    double a_abs = 0.0, s_abs = 0.0, da_max = 0.0, ds_max = 0.0;
  };
  struct Block {
    size_t first = 0, last = 0;  // grid points [first, last)
    LineBounds up, down;         // where P > 0, where P < 0
  };
  std::vector<Block> blocks_;
};

// ---- Cut-off sweep (Chawda, Celik and O'Malley's question, answered exactly):
// for each cut-off, the loop with a first-order low-pass velocity filter and the
// measure; the best cut-off maximises it.
enum class SweepMeasure {
  kKcrMax,  // K_CR^max of Summarize() [N m/rad]
  kArea,    // area of the stable (B, K) set for 0 <= B <= area_B_max [N m/rad x N m s/rad],
            // K_hi = +inf clipped at area_K_clip
};
std::string ToString(SweepMeasure m);
SweepMeasure SweepMeasureFromString(const std::string& s);  // "kcr-max" | "area"; InputError otherwise

struct CutoffSweepOptions {
  std::vector<double> cutoffs_hz;  // each in (0, 1/(2T)); not empty
  SweepMeasure measure = SweepMeasure::kKcrMax;
  double area_B_max = std::numeric_limits<double>::quiet_NaN();  // [N m s/rad], > 0 for kArea
  double area_K_clip = std::numeric_limits<double>::infinity();  // [N m/rad], > 0
  int area_B_points = 200;  // trapezoid points on [0, area_B_max], >= 2
  bool IsValid(double period_s, std::string* why) const;
};

struct CutoffSweepResult {
  std::vector<double> cutoffs_hz, measure;  // one per cut-off
  std::vector<DelaySummary> summaries;
  int best = -1;  // index of the largest finite measure; -1 = none finite
  // The same measure without a velocity filter (the hand kept): a filter is
  // worth having only where it beats this.
  double unfiltered = std::numeric_limits<double>::quiet_NaN();
  // The best is the first or the last cut-off: the optimum may lie outside
  // the swept range.
  bool best_at_edge = false;
};

// The hand in `loop` is kept; its filter is replaced by each low-pass.
CutoffSweepResult SweepCutoff(const model::Plant& plant, double period_s, int delay_samples,
                              const LoopOptions& loop, const CutoffSweepOptions& options);

// Area of the stable set of z for 0 <= B <= B_max (trapezoid on `points` values of B).
double StableArea(const ZWidth& z, double B_max, double K_clip, int points);

}  // namespace zwidth::stability
