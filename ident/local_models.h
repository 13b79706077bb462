// The local polynomial method (LPM: Pintelon, Schoukens, Vandersteen and
// Barbe, "Estimation of nonparametric noise and FRF models for multivariable
// systems, Part I: Theory", MSSP 24(3), 2010) and the local rational method
// (LRM: McKelvey and Guerin, "Non-parametric frequency response estimation
// using a local rational model", SYSID 2012) on the full-record DFT.
//
// The DFT of a finite record of y = G u + v is, exactly,
//   Y(k) = G(z_k) U(k) + T(z_k) + V(k),
// with T = I(z)/A(z) the transient (what Welch's window turns into leakage):
// smooth in k, with G's poles. Around each bin k, over the 2n + 1 bins
// k + r, r = -n..n (shifted inside 1..N/2 - 1 at the ends: DC and Nyquist are
// never used), a local model is fitted by linear least squares:
//   LPM  G(k + r) = sum_{s<=R} g_s r^s,  T(k + r) = sum_{s<=R} t_s r^s;
//   LRM  G = N(r)/D(r), T = M(r)/D(r), D(0) = 1, linearised as
//        D(r) Y = N(r) U + M(r) + residual (N, M of order R, D of order R_D).
// The estimate is G(k) = g_0 (LPM) or n_0 (LRM). Columns are scaled (r by n,
// then each to unit norm); the transient's real columns are projected out
// per bin and the rest solved by a small Householder QR (docs/estimators.md,
// "The solver").
//
// The rigid body. Eq. (1)'s 1/(m s^2 + b s) is a double pole at z = 1 in the
// sampled plant (and in T: a drift of the position over the record), steep
// near DC where m and b are set: over 15 bins at bin 21 (0.7 Hz of a 30 s log)
// 1/k^2 changes by a factor 4, which no quadratic follows. So the output is
// differenced first, y'[t] = ((1 - z^-1)^d y)[t] for t = d..N-1 (the input
// taken over the same samples): G' = (1 - z^-1)^d G has no pole at z = 1 and
// its transient none either; each equation (row) is divided by
// |1 - e^{-j theta_j}|^d so that the noise stays white, and
// G(k) = G'(k) / (1 - e^{-j theta_k})^d. Default d = 2 (eq. (1)'s double pole).
//
// Variance. The residual E of the 2n + 1 (times the runs) equations has
// q = rows - parameters degrees of freedom: sigma^2 = |E|^2 / q (unbiased for
// white noise over the window), and G(k) - G = c_k^T V over the rows, so
// var G(k) = sigma^2 |c_k|^2 and, as the windows of k and k + l share rows,
// cov(G(k), G(k + l)) = sigma^2 sum_j c_k(j) conj(c_{k+l}(j)): the error
// correlation passed to the fit (FrequencyResponse::error_correlation).
//
// Several runs (records of equal length; longer ones are cut to the
// shortest): one least-squares problem per bin, G (and the LRM's D) shared, a
// transient per run. Closed loop (a logged excitation r): the local model of
// r -> u and of r -> y, and G = G_ry / G_ru with its variance by the delta
// method from the two channels' residual covariance (as ident/joint.h does
// for Welch).
#pragma once

#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "ident/joint.h"
#include "ident/welch.h"

namespace zwidth::ident {

enum class LocalMethod { kPolynomial, kRational };
std::string ToString(LocalMethod m);                      // "lpm", "lrm"
bool FromString(const std::string& s, LocalMethod* m);

struct LocalModelOptions {
  LocalMethod method = LocalMethod::kRational;
  // Bins either side of the estimated one (the window is 2 half_width + 1
  // bins); 0 = the method's default: LPM 6 (13 bins), LRM 7 (15 bins), which
  // leave q = 7 residual degrees of freedom per bin and run with the default
  // orders (see docs/estimators.md). >= 1; with the orders it must leave q >= 1.
  int half_width = 0;
  // LPM: order R of the polynomials of G and T; LRM: order of N and M. In [0, 6].
  int order = 2;
  // LRM only: order R_D of the common denominator D (D(0) = 1). In [1, 6].
  int denominator_order = 2;
  // Times the output is differenced before the local model (the rigid body's
  // poles at z = 1 taken out; see above). In [0, 2].
  int differences = 2;
  double fmin_hz = 0.7;  // lowest bin kept [Hz], >= 0
  double fmax_hz = std::numeric_limits<double>::infinity();  // highest [Hz], > fmin_hz; clipped below Nyquist

  int HalfWidth() const;                 // half_width, or the method's default
  int NumParameters(int runs) const;     // unknowns of one bin's least squares
  bool IsValid(std::string* why) const;  // the message names the field
};

// One run: input u and output y, and in closed loop the logged excitation r
// (else empty), all of one length.
struct LocalRecord {
  std::vector<double> u, y, r;
};

struct LocalEstimate {
  // H, H_std (each part), error_correlation (lags 1..2 half_width), estimator
  // ("lpm", "lrm", "-joint" appended in closed loop); S_uu, S_yy, S_uy: the
  // periodograms' means over each bin's window (one-sided PSD); coherence:
  // the local signal-to-total ratio |G|^2 S / (|G|^2 S + sigma^2) (r -> y in
  // closed loop); num_averages = effective_averages = q; window_length = the
  // samples per run used; bin_correlation = 1 + 2 sum_l Re error_correlation_l
  // (at least 1): the variance inflation of a sum over adjacent bins.
  FrequencyResponse frf;
  // Per bin: the transient (leakage) term at the bin relative to the
  // response's part, |T(k)| / |G(k) U(k)| (the largest over the runs; in
  // closed loop of the r -> y channel). Welch's H1 carries an error of this
  // order where the transient is not removed.
  std::vector<double> transient_ratio;
  int residual_dof = 0;       // q
  int samples_per_run = 0;    // after cutting to the shortest run (before differencing)
  std::vector<std::string> warnings;  // e.g. runs cut to the shortest
};

// Throws InputError for invalid options, runs of unequal u/y/r lengths, a
// log too short for the window (naming the samples needed), or no bin in
// [fmin_hz, fmax_hz].
LocalEstimate EstimateLocal(const std::vector<LocalRecord>& runs, double sample_rate_hz,
                            const LocalModelOptions& options);

// The estimate as the combined response the fit and the files take.
CombinedResponse ToCombined(LocalEstimate estimate, LocalMethod method, int num_runs);

}  // namespace zwidth::ident
