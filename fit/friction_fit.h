// Coulomb friction identified together with the linear model of eq. (1),
// from the time-domain log, seeded by the frequency-domain fit (FitModel).
//
// Model: friction acts on the rigid body, where the motor torque does
// (model/friction.h), and the sections act on its position:
//   m x'' + b x' = u(t - D T) + offset - F_c sign(x'),   y = prod_i M_i(s) x.
// While the body moves, an asymmetric friction (F_c+, F_c-) and an offset are
// one and the same thing (F_c+ - offset, F_c- + offset), so the fit estimates
// the symmetric level F_c and the offset; the breakaway level is not
// identified (samples at rest are dropped).
//
// Method: the inverse-model least squares of the EMPS benchmark's reference
// (IDIM-LS; Janot, Gautier et al.), with its errors-in-variables problem
// removed by taking m from the frequency-domain fit, iterated:
//   1. the rigid body's velocity and acceleration from the encoder by a
//      zero-phase band-limited differentiation (one FFT of the whole log: the
//      position, with the straight line through its ends removed, times
//      j w / prod M_i(j w) and a low-pass L(f): 1 up to cutoff_hz, a cos^2
//      taper to 0 at 1.5 cutoff_hz); the torque through the same L, delayed
//      by D + 1/2 samples and weighted by sinc(f T) (the ZOH, exact below
//      Nyquist); the regressor sign(v) through L too (parallel filtering);
//   2. least squares over every q-th sample (q: the decimation that L's band
//      allows, so that the rows are nearly uncorrelated and the OLS std
//      holds), away from the log's ends, where |v| >= min_speed_fraction
//      rms(v):  u - m a = b v + F_c L[sign v] - offset;
//   3. the friction torque removed from the input (u' = u - F_c sign(v) +
//      offset while moving; u' = 0 while stuck: v ~ 0 and |u + offset| <=
//      F_c), its response estimated (Welch, as the linear fit's) and refitted
//      (FitModel, the seed's order and delay, started from the last plant):
//      the new m and sections go back to step 1.
// Why not regress m too: the acceleration of a quantised encoder is noisy
// (errors in variables) and biases m down by tens of % on a 4000-count
// encoder; the frequency response fixes m well above the friction's band.
// Why not an output-error fit of the nonlinear model: a stick-slip simulation
// per cost evaluation is slow, and its cost is not smooth in F_c.
//
// Step 2 (since 2026-12-02) is solved in the frequency domain: the same
// equation per DFT bin below the cutoff, divided by the encoder error's gain
// j w (m j w + b) / prod M_i (an output-error weighting that puts b's weight
// at the rigid-body corner, where b shows, instead of in the differentiated
// encoder's noise), with the simulated body's position as the instrument of
// b's column (no errors in variables), a transient of three real terms, and
// the offset from the time-domain rows. b and F_c are the fixed point of
// "simulate with (b, F_c), regress", found by a safeguarded Newton method;
// their covariance is the fixed point's (friction_fit.cc, SimulatedIdim),
// with m's std propagated.
//
// Step 2's regressor sign(v) comes from the rigid body with friction simulated
// exactly from the measured torque (events at v = 0; incrementally stable, so
// it follows the device), not from the band-limited velocity: under a white
// torque the velocity changes sign faster than the rigid-body band, and
// sign(L[v]) underestimates F_c by a third (measured: 5.4 for 8 mN m). The
// detection (friction_fit.cc, Detect) uses two cheap tests unbiased at
// F_c = 0: the time-domain rows on sign(L[v]), and the frequency-domain rows
// on sign(v) of the body simulated without friction (a coarse encoder's
// noise swamps the first); friction is detected when either's F_c / std
// exceeds detection_z and its equivalent damping would put the linear b
// more than 3 std off.
//
// Two topologies (FrictionTopology), both fitted (2026-12-02): friction
// opposing the rigid body's velocity x' with the sections after it on the
// output (tests/friction_sim.h), or opposing the collocated motor/encoder
// velocity y' at the plant input (model::StickSlipPlant, `zwidth simulate
// --coulomb`: while y' = 0 it holds the torque that keeps y' at 0, and the
// sections keep moving). Both obey m X'' + b X' = u + offset + f with
// X = Y / prod M_i; they differ in when f switches and what it is at rest, so
// the first round of steps 1-3 runs for each topology (its own simulation of
// the regressor and the rest phases) and the one whose frequency-domain IDIM
// leaves the smaller weighted residual (the encoder's error, step 2) is
// iterated on. Measured on Table I with 40960
// counts at 13 % of the torque rms: the wrong topology biased F_c by -50 %
// and b by +79 %.
//
// The reported plant is the last refit's (m, sections, their std from its
// covariance), with b from whichever of the refit and step 2 has the smaller
// std, the refit's std including what std(F_c) does to it (friction_fit.cc,
// ChooseB); F_c and the offset from step 2 with their OLS std.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fit/fit.h"
#include "ident/welch.h"
#include "model/friction.h"

namespace zwidth::fit {

// What the fit does about friction.
enum class FrictionModel {
  kNone,     // the linear fit; friction only detected (the verdict's `friction` reason)
  // friction fitted when detected (F_c / std > detection_z, and relevant), else the linear
  // fit; when detected weakly (F_c / std in (2, detection_z]) fitted too and kept only if
  // its b is inconsistent (beyond 3 std) with the linear fit's
  kAuto,
  kCoulomb,  // friction always fitted
};
std::string ToString(FrictionModel f);
// "none", "auto", "coulomb"; false for another word.
bool FrictionModelFromString(const std::string& s, FrictionModel* f);

// Where the Coulomb friction acts (see above).
enum class FrictionTopology {
  kRigidBody,   // opposes the rigid body's velocity; the sections act after it on the output
  kCollocated,  // opposes the encoder's (collocated motor) velocity at the plant input
};
std::string ToString(FrictionTopology t);
// "rigid body", "collocated"; false for another word.
bool FrictionTopologyFromString(const std::string& s, FrictionTopology* t);

struct FrictionFitOptions {
  FrictionModel model = FrictionModel::kAuto;
  // Upper edge of the band used [Hz]; 0 = automatic: 0.4 x the lowest pole or
  // zero frequency of the seed's sections, at most 0.04 x the sample rate
  // (the EMPS reference's 40 Hz at 1 kHz). Else in (0, 0.3 x sample rate].
  double cutoff_hz = 0.0;
  // Samples whose |v| is below this fraction of v's rms are not used (stick,
  // where friction is not F_c sign v), in [0, 1).
  double min_speed_fraction = 0.0;
  int iterations = 6;          // IDIM + refit rounds, in [1, 20] (converged by 4-5 on the tests' logs)
  double detection_z = 5.0;    // F_c / std(F_c) above which friction is detected, > 0
  ident::WelchOptions welch;   // the refit's estimate (use the linear fit's)
  bool linear = false;         // the units its message names (model/units.h): a linear axis's N, m

  bool IsValid(std::string* why) const;
};

enum class FrictionFitStatus {
  kNotRun,       // sentinel
  kFitted,       // friction fitted: `fit` is the linear part, `friction` its Coulomb level
  kNotDetected,  // no significant friction (or model kNone): `fit` is the linear fit
  // Friction asked for or detected, but not identified from this log (the
  // message says why and what to record instead): too few usable rows for the
  // band, a refit that did not converge, a fixed point not found, or values
  // the log does not determine (b within 1 std of 0; with FrictionModel::kAuto
  // F_c within 2 std of 0, which kCoulomb reports as fitted; a non-finite
  // value or std, an offset beyond 10 x the torque rms). `fit` is the linear
  // fit, with a warning, and the `friction` reason when detected; `friction`
  // holds the rejected estimate for the record, never to be used.
  kNotIdentified,
};
std::string ToString(FrictionFitStatus s);

struct FrictionFitResult {
  FrictionFitStatus status = FrictionFitStatus::kNotRun;
  std::string message;
  // The detection on the linear fit's plant (friction_fit.cc, Detect): two
  // tests of F_c = 0, each's F_c / std, and the estimate of the one with the
  // larger (detected: it exceeds FrictionFitOptions::detection_z).
  bool detected = false;
  double detection_coulomb = 0.0, detection_coulomb_std = 0.0;
  double detection_time_domain_z = 0.0, detection_frequency_domain_z = 0.0;
  // The last IDIM: coulomb_pos = coulomb_neg = F_c, offset; std alike.
  model::Friction friction, friction_std;
  double idim_b = 0.0, idim_b_std = 0.0;  // b of the last IDIM [N m s/rad]
  // The last IDIM's plant (m, sections, delay: the refit before the last),
  // its std (propagated into b's and F_c's), and its fixed point's Jacobian
  // d(G(x) - x)/dx at x = (idim_b, F_c), the offset held, row-major, from
  // which their std comes (NaN when not run).
  model::Plant idim_plant, idim_plant_std;
  std::array<double, 4> fixed_point_jacobian{};
  double cutoff_hz = 0.0;
  int rows_used = 0;
  int decimation = 1;
  int iterations = 0;
  double linear_b = 0.0, linear_b_std = 0.0;  // the linear-only fit's b
  // The topology kept (kFitted, kNotIdentified), and each topology's IDIM residual
  // after the first round, which chose it (the weighted frequency-domain
  // rows' rms; inf when its first refit was tried and failed: the other's is
  // tried only when the chosen one's fails).
  FrictionTopology topology = FrictionTopology::kRigidBody;
  double rigid_body_residual_rms = 0.0, collocated_residual_rms = 0.0;
  // The linear part: the refit when kFitted, else the linear fit (with the
  // `friction` reason when friction was detected and not fitted).
  FitResult fit;
};

// One log (input torque, encoder position, uniformly sampled). `linear` is
// FitModel's converged result on this log's response with `fit_options`.
// Throws InputError for invalid options; a log too short for the band (fewer
// than 200 time-domain rows or 100 frequency bins) is kNotIdentified.
FrictionFitResult FitFriction(const std::vector<double>& input, const std::vector<double>& output,
                              double sample_rate_hz, const FitResult& linear, const FitOptions& fit_options,
                              const FrictionFitOptions& options);

// The verdict's `friction` reason (fit/quality.cc): appended to r, which is
// then poor, when a linear fit was kept on a log that shows friction.
void AddFrictionReason(const FrictionFitResult& ff, FitResult* r);

}  // namespace zwidth::fit
