// Frequency responses from several runs, closed-loop logs and whole records,
// built on the Welch spectra of ident/welch.h.
//
// Closed loop. A device held by a controller while an external excitation r
// is added: u (torque) and y (position) both respond to r and to the noise fed
// back through the controller, so H1 = S_uy / S_uu is biased wherever the fed
// back noise is comparable to the excitation. The joint input-output estimate
//   G = S_ry / S_ru
// (Wellstead, "Non-parametric methods of system identification", Automatica
// 17(1), 1981; Pintelon & Schoukens, "System Identification: A Frequency
// Domain Approach", 2nd ed., 2012, ch. 2, FRF measurement under feedback) uses
// only what is correlated with r, which the noise is not.
// Its per-bin variance, derived by the delta method on the averaged cross
// spectra: G_hat - G ~ (S_ry_hat - G S_ru_hat) / S_ru = mean(conj(R) E) / S_ru
// with E = Y - G U (uncorrelated with R), so for n_d independent averages of
// circular Gaussian spectra
//   var(G_hat) = S_rr S_ee / (n_d |S_ru|^2),
//   S_ee = S_yy - 2 Re(G conj(S_uy)) + |G|^2 S_uu,
// and sd of each of the real and imaginary parts = sqrt(var / 2). With r = u it
// is Bendat & Piersol's H1 formula |H| sqrt((1 - g^2) / (2 n_d g^2)).
//
// Several runs: spectra are averaged weighted by their segment counts, and the
// equivalent averages n_d add up.
// Whole record: each run is one rectangular segment (a swept sine or a whole
// number of periods of a multisine); then the coherence of a run is 1 by
// construction and the per-bin std comes from the scatter of the per-run
// estimates H_i about the combined H: sd (per part) = sqrt(sum |H_i - H|^2 /
// (2 M (M - 1))) for M runs (infinite for one run).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ident/welch.h"

namespace zwidth::ident {

// The spectra of one run: Welch of (u, y), and with an excitation r logged
// Welch of (r, u) and of (r, y) (same options, same samples).
struct RunSpectra {
  FrequencyResponse uy;
  std::optional<FrequencyResponse> ru, ry;
};

// Spectra of one run from whole signals; r may be empty (open loop).
RunSpectra EstimateRun(const std::vector<double>& u, const std::vector<double>& y,
                       const std::vector<double>& r, double sample_rate_hz, const WelchOptions& options);

enum class StdSource {
  kCoherence,   // Bendat & Piersol / the delta-method formula above, n_d averages
  kRunScatter,  // scatter of the per-run estimates (whole records)
};
// kLpm, kLrm: the local methods of ident/local_models.h (open or closed loop:
// frf.estimator says which).
enum class CombinedMethod { kH1, kH2, kJoint, kLpm, kLrm, kRobust };
std::string ToString(CombinedMethod m);

struct CombinedResponse {
  CombinedMethod method = CombinedMethod::kH1;
  // H = G (joint) or H1/H2; S_uu, S_yy, S_uy averaged over the runs;
  // coherence = u->y, or r->y for the joint estimate; H_std per part.
  FrequencyResponse frf;
  std::vector<double> coherence_ru, coherence_ry;  // joint estimate only
  int num_runs = 0;
};

// Combines runs of one device (all with the same window, rates within 0.1 %
// (run 1's is used), and all with or without r). Throws InputError when they
// differ.
CombinedResponse CombineRuns(const std::vector<RunSpectra>& runs, Estimator estimator, StdSource std_source);

}  // namespace zwidth::ident
