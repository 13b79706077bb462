// The Z-width: the (K, B) a device renders stably in the sampled loop of eq. (2),
//
//   1 + z^-d (K + B (1 - z^-1)/T) G_d(z) = 0,
//
// with G_d the exact ZOH plant (including the model's own input delay, which
// adds to d). On z = e^{j theta} the equation is linear in K and B
// (D-decomposition): with W(theta) = -z^d / G_d(z),
//
//   K + (B/T)(1 - cos theta) = Re W,     (B/T) sin theta = Im W,
//
// so each theta in (0, pi) is a boundary point B(theta) = T Im W / sin theta,
// K(theta) = Re W - Im W tan(theta/2), and theta = pi adds the real crossing
// K = Re W(pi) - 2B/T. For a given B the crossings are the roots of
// B(theta) = B. B(theta) does not depend on B, so it is tabulated once on a
// grid that is dense near every resonance and antiresonance, its extrema are
// refined, and each monotone piece holds at most one root, found by Brent's
// method. Every K_CR is verified by a Schur-Cohn test of the closed-loop
// polynomial just below and just above it.
#pragma once

#include <atomic>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "model/plant.h"
#include "stability/loop_options.h"
#include "stability/sampled_plant.h"

namespace zwidth::stability {

class ClosedLoopMatrix;

// Schur-Cohn decides only where rounding the characteristic polynomial moves
// the boundary by at most this, relative (ZWidth::polynomial_error): 1e-3 of
// the smallest offset at which the Z-width probes a boundary's sides (1e-6).
constexpr double kPolynomialRelativeTolerance = 1e-9;
// The same bound under which Schur-Cohn may verify the ends (K_cr and the
// intervals' ends at 1 -+ 1e-6) where the eigenvalues decide the rest.
constexpr double kPolynomialVerifyTolerance = 1e-8;

struct BoundaryOptions {
  int min_grid_points = 2048;    // uniform theta grid on (0, pi), >= 64
  int grid_points_per_delay = 64;  // extra resolution for the delay's phase, >= 8
  double theta_tolerance = 1e-13;  // Brent tolerance on theta [rad]
  bool verify = true;              // Schur-Cohn check of each K_CR
  bool IsValid(std::string* why) const;
};

struct Crossing {
  double theta = 0.0;  // rad/sample
  double K = 0.0;      // N m/rad at which a closed-loop pole is at e^{j theta}
  // How the root(s) cross the circle as K increases through K at this B:
  // +1 outward, -1 inward, 0 not known (a tangency, or a derivative lost to
  // rounding). See ZWidth::Crossings.
  int direction = 0;
};

struct CriticalPoint {
  double B = 0.0;
  // Smallest K > 0 with a closed-loop pole on the unit circle; 0 when the loop
  // is already unstable as K -> 0+; +inf when no crossing exists.
  double K_cr = std::numeric_limits<double>::quiet_NaN();
  double f_cr_hz = std::numeric_limits<double>::quiet_NaN();  // ultimate frequency
  bool unstable_at_zero_k = false;
  // Schur-Cohn agrees: stable at 0.999999 K_cr, unstable at 1.000001 K_cr
  // (with ill-conditioned poles, ZWidth::UnstableRoots: the eigenvalues at
  // the smallest of K_cr (1 -+ 1e-6 .. 1e-3) they can resolve).
  bool verified = false;
  // The paper's reading, eq. (4): the gain margin of
  // G_d / (z^d + B (1 - z^-1)/T G_d) as MATLAB's margin() reports it (the phase
  // crossover whose margin is nearest 0 dB). It ignores whether the loop with
  // K = 0 is stable, so past B_max it is positive where no K is stable.
  double K_margin = std::numeric_limits<double>::quiet_NaN();
  double f_margin_hz = std::numeric_limits<double>::quiet_NaN();
  bool AgreesWithMargin(double rel_tol = 1e-6) const;
};

// One maximal interval K_lo < K < K_hi of stiffness at a fixed B in which every
// closed-loop pole of eq. (2) lies strictly inside the unit circle. Its ends
// are D-decomposition crossings (or 0 / +inf); the number of unstable roots
// only changes at a crossing, so one Schur-Cohn test inside each region
// between consecutive crossings decides the whole region.
struct KInterval {
  double K_lo = 0.0;  // N m/rad, >= 0; 0 means "from K = 0+"
  double K_hi = std::numeric_limits<double>::infinity();  // N m/rad, may be +inf
  double f_lo_hz = std::numeric_limits<double>::quiet_NaN();  // pole frequency at K_lo (nan at 0)
  double f_hi_hz = std::numeric_limits<double>::quiet_NaN();  // pole frequency at K_hi (nan at inf)
  // Schur-Cohn agrees at each finite, positive end: stable at (1 -+ 1e-6) of
  // it inside the interval, unstable just outside (ill-conditioned poles: as
  // CriticalPoint::verified).
  bool verified = false;
};

// The stable set at one B for several loops (e.g. a range of hands): the
// intersection of their interval sets. Ends keep the frequency of the loop that sets them.
std::vector<KInterval> IntersectIntervals(const std::vector<KInterval>& a, const std::vector<KInterval>& b);

// A B range past B_max_from_zero in which some K > 0 is stable again (the
// stable K interval there starts above 0).
struct ReopenedBand {
  double B_lo = 0.0;   // N m s/rad: where the band starts (B_max_from_zero when contiguous)
  double B_hi = 0.0;   // N m s/rad: where the last stable K disappears
  double K_max = 0.0;  // N m/rad: largest stable K seen in the band (on the scan of Summarize)
};

// A jump of the critical frequency f_CR(B): another branch of the boundary
// takes over K_CR there (K_CR is continuous or jumps too).
struct FrequencyJump {
  double B = 0.0;  // N m s/rad
  double K_before = 0.0, K_after = 0.0;         // K_CR just below and just above B [N m/rad]
  double f_before_hz = 0.0, f_after_hz = 0.0;   // f_CR just below and just above B
};

struct DelaySummary {
  int delay_samples = 0;   // loop delay d (the model's own delay is added)
  double K_cr_at_zero_B = std::numeric_limits<double>::quiet_NaN();
  double f_at_zero_B_hz = std::numeric_limits<double>::quiet_NaN();
  // B_t as the paper defines it (section III): where K_CR(B) peaks and f_CR
  // jumps, i.e. of the frequency_jumps the one with the largest K_CR (on a
  // device with several modes f_CR can jump earlier, at a lower K_CR).
  // f_before_hz / f_after_hz are that jump's.
  bool has_transition = false;
  double B_t = std::numeric_limits<double>::quiet_NaN();
  double K_cr_max = std::numeric_limits<double>::quiet_NaN();    // max of K_CR(B)
  double B_at_K_cr_max = std::numeric_limits<double>::quiet_NaN();
  double f_before_hz = std::numeric_limits<double>::quiet_NaN();
  double f_after_hz = std::numeric_limits<double>::quiet_NaN();
  // The B where the interval from K = 0+ closes (K_CR(B) reaches 0): what the
  // paper and zwidth before issue 13 called B_max.
  double B_max_from_zero = std::numeric_limits<double>::infinity();
  // The largest B at which some K > 0 is stable (reopened bands included).
  // Found on a scan of B up to a proven bound (every stable region is bounded
  // above by a crossing with K > 0, and no crossing with K > 0 exists past the
  // largest B of the D-decomposition curve with K > 0); a band narrower than
  // the scan spacing (1/1000 of that bound, plus 1000 geometric points from
  // 1e-6 of it and both sides of every fold and K = 0 point of the curve) can
  // be missed.
  double B_max = std::numeric_limits<double>::infinity();
  std::vector<ReopenedBand> reopened_bands;
  // Every jump of f_CR on [0, B_max_from_zero), ascending in B (found on a
  // 200-point scan: jumps closer together than its spacing count once).
  std::vector<FrequencyJump> frequency_jumps;
  // The stability test used (ZWidth::uses_polynomial_test) and its
  // conditioning: ZWidth::polynomial_error, SampledPlant::denominator_pole_shift.
  bool polynomial_test = true;
  double polynomial_error = std::numeric_limits<double>::quiet_NaN();
  double pole_shift = std::numeric_limits<double>::quiet_NaN();
  // The sampled plant's pole conditioning (SampledPlant::conditioning), and a
  // warning (empty: none) when the eigenvalue test decides and
  // conditioning.eigenvalue_shift > kEigenvalueShiftWarning: rounding can
  // then move a pole by more than 1e-6 of its distance to the unit circle,
  // the neighbourhood of a boundary outside which the answers are stated
  // exact, so points that close rest on the last digits of the eigenvalues. Schur-Cohn is used only where its own bounds hold.
  PoleConditioning conditioning;
  std::string conditioning_warning;
};

// The warning of DelaySummary::conditioning_warning for a test and a
// conditioning: the rule, once.
std::string ConditioningWarning(bool polynomial_test, const PoleConditioning& c);
// Why the eigenvalues decide a summary's stability (empty when Schur-Cohn
// does): the bound of ZWidth::ChooseStabilityTest that failed, with its value.
std::string StabilityTestNote(const DelaySummary& s);

// Standard deviations [same units as the quantity] of the summary's quantities
// from a parameter covariance (stability/uncertainty.h); nan = not computed.
struct SummaryStd {
  double K_cr_at_zero_B = std::numeric_limits<double>::quiet_NaN();
  double B_t = std::numeric_limits<double>::quiet_NaN();
  double K_cr_max = std::numeric_limits<double>::quiet_NaN();
  double B_max = std::numeric_limits<double>::quiet_NaN();
};

// The B values of a boundary table, shared by `boundary` and `run`.
// Default: b_points values from b_min to 1.05 x the largest stable B of the
// device (B_max over the delays), so the grid scales with the device;
// b_step, when given, wins over b_points.
struct BGridOptions {
  double b_min = 0.0;  // first B [N m s/rad], finite, >= 0
  double b_max = std::numeric_limits<double>::quiet_NaN();   // last B [N m s/rad]; nan = automatic
  double b_step = std::numeric_limits<double>::quiet_NaN();  // B step [N m s/rad], > 0; nan = from b_points
  int b_points = 1000;  // number of B values when b_step is not given, in [2, kMaxBGridValues]
  bool IsValid(std::string* why) const;  // names the field: "BGridOptions::b_step must be ..."
};
// Cap on B values x delays of one table (about 100 MB of CSV).
constexpr double kMaxBGridValues = 1e6;
// largest_stable_B: B_max over the delays (may be 0 or inf); fallback_B: the
// range used when that is not finite and positive. Throws InputError (naming
// --b-min, --b-max, --b-step or --b-points) for an invalid or too large grid;
// never overflows (counts are computed in double first).
std::vector<double> MakeBGrid(const BGridOptions& options, double largest_stable_B, double fallback_B,
                              int num_delays);

class ZWidth {
 public:
  // The loop of one delay on a sampled plant shared with other delays (the
  // ZOH, N(z)/D(z) and the mode patches are not recomputed). loop.hand must be
  // the sampled plant's hand (std::invalid_argument otherwise: a broken
  // contract). Throws InputError for an invalid delay, loop or options.
  ZWidth(const SampledPlant& sampled, int delay_samples, const LoopOptions& loop = {},
         const BoundaryOptions& options = {});
  // Convenience: samples the plant for this one loop. Throws InputError for an
  // invalid plant, period or delay.
  ZWidth(const model::Plant& plant, double period_s, int delay_samples,
         const BoundaryOptions& options = {});
  // The generalised loop of stability/loop_options.h: velocity filter F(z) and
  // the user's hand. With W = -z^D / G_h and V = F(z)(1 - z^-1)/T the crossing
  // condition on the circle is K + B V = W: B = Im W / Im V, K = Re W - B Re V
  // (theta = pi: K = W(pi) - B V(pi), V(pi) = 2 F(-1)/T real). The
  // characteristic polynomial, multiplied through by F's denominator, is
  //   z^{D+1} D(z) F_d(z) + (K z F_d(z) + (B/T)(z - 1) F_n(z)) N(z).
  // Throws InputError for invalid loop options.
  ZWidth(const model::Plant& plant, double period_s, int delay_samples, const LoopOptions& loop,
         const BoundaryOptions& options = {});

  CriticalPoint At(double B) const;
  // Every K at which a closed-loop root is on the unit circle at this B, with
  // the direction it crosses in. On the circle the roots solve
  // g(z) = W(z) - B V(z) = K, so dz/dK = 1/g'(z), and with z = e^{j theta}
  // the root moves outward exactly when Im(dg/dtheta) > 0. Off theta = pi,
  // Im g(theta) = Im V(theta) (B(theta) - B), whose derivative at the
  // crossing is Im V B'(theta): the sign of Im V times the direction of the
  // monotone piece of B(theta) the crossing lies on. At theta = pi (one real
  // root), g'(-1) < 0 on the real axis.
  std::vector<Crossing> Crossings(double B) const;
  // Schur-Cohn on the closed-loop polynomial; K = 0 is taken as 0+ (the pole
  // at z = 1 that K = 0 leaves on the circle moves inside for K > 0).
  bool IsStable(double K, double B) const;
  // The number of closed-loop roots with |z| >= 1 at (K, B) (K = 0 as 0+):
  // exact with the eigenvalue test, 0 or 1 (at least one) with Schur-Cohn.
  // Where the sampled plant's poles are ill-conditioned (its
  // eigenvalue_shift over kEigenvalueShiftWarning: the summary's
  // conditioning warning) the eigenvalues at K = 0+ and the crossings'
  // directions count it (exact to the crossings' theta tolerance; the
  // eigenvalues only where a direction is unknown).
  // IsStable is UnstableRoots == 0: every caller's one test.
  int UnstableRoots(double K, double B) const;
  DelaySummary Summarize() const;
  // All stable K intervals at this B, ascending. Empty when no K > 0 is stable.
  std::vector<KInterval> StableIntervals(double B) const;
  // At(B) and StableIntervals(B) together (a boundary row): the same values
  // as the two calls, with the crossings found once and no stability test run
  // twice.
  struct Row {
    CriticalPoint point;
    std::vector<KInterval> intervals;
  };
  Row RowAt(double B) const;
  // The four quantities of SummaryStd recomputed near a nominal summary of a
  // nearby plant (local brackets of +-2%; nan where the bracket fails). Used for
  // the finite-difference delta method.
  SummaryStd SummarizeNear(const DelaySummary& nominal) const;

  int total_delay() const { return total_delay_; }
  const LoopOptions& loop() const { return loop_; }
  double period_s() const { return period_s_; }
  const SampledPlant& sampled_plant() const { return sp_; }
  // Closed-loop characteristic polynomial coefficients (z^0 first). Its
  // roots are only as good as polynomial_root_error() says.
  std::vector<double> CharacteristicPolynomial(double K, double B) const;
  // How far rounding the characteristic polynomial's coefficients moves the
  // boundary: the largest relative dK/K (or dB/B) over the D-decomposition
  // curve (nan when D(z)'s own poles already move too far:
  // SampledPlant::denominator_pole_shift). At most kPolynomialRelativeTolerance:
  // IsStable runs Schur-Cohn on the polynomial (O(n^2)); else the eigenvalues
  // of the closed-loop state matrix (stability/closed_loop.h, O(n^3),
  // backward stable).
  double polynomial_error() const { return polynomial_error_; }
  // The B > 0 where the K = 0 boundary is crossed (sorted), and the change
  // of the number of roots outside at K = 0+ as B grows past each: +-2 for a
  // pair on the circle, +-1 at theta = pi, 0 where its sign is not known.
  // Between two, UnstableRoots(0, B) is constant.
  const std::vector<double>& zero_k_boundary() const { return zero_k_b_; }
  const std::vector<int>& zero_k_changes() const { return zero_k_change_; }
  bool uses_polynomial_test() const { return use_polynomial_; }

 private:
  // A monotone piece of B(theta); grid points ia..ib lie strictly inside it.
  struct Segment { double ta, tb, Ba, Bb; int ia, ib; };
  // The theta grid, B(theta) and K(theta) on it, and its monotone pieces.
  void BuildGrid();
  void Point(double theta, double* B, double* K) const;
  // Bisection for the B where f_CR jumps between f_lo (at b_lo) and f_hi.
  double FindTransition(double b_lo, double b_hi, double f_lo, double f_hi) const;
  double HzOf(double theta) const;
  // Largest B of the D-decomposition curve (and of the theta = pi line) with K > 0.
  double StableBBound() const;
  // The three parts of Summarize.
  std::vector<double> ZeroKBoundary(const CriticalPoint& c0, DelaySummary* s) const;
  void ScanStableB(const std::vector<double>& cand, DelaySummary* s) const;
  void ScanKcrMax(const CriticalPoint& c0, const std::vector<double>& cand, DelaySummary* s) const;
  // V(theta) = F(e^{j theta})(1 - e^{-j theta})/T.
  std::complex<double> V(double c, double s) const;
  // At and StableIntervals from the crossings at B, with `stable(K)` deciding
  // IsStable(K, B). kVerify runs the Schur-Cohn checks of options_.verify
  // (they set only the `verified` flags, never a value); kValuesOnly does
  // not; kFirstOnly (intervals) also stops at the first stable region.
  enum class Check { kVerify, kValuesOnly, kFirstOnly };
  template <typename Stable>
  CriticalPoint PointFrom(double B, const std::vector<Crossing>& xs, const Stable& stable, Check check) const;
  template <typename Stable>
  // use_directions: the counts follow the crossings' directions (eigenvalue
  // test only; tested regions are K -> 0+ and those after a crossing of
  // unknown direction); an interval the verification does not confirm makes
  // it test every region instead.
  std::vector<KInterval> IntervalsFrom(double B, const std::vector<Crossing>& xs, const Stable& stable, Check check,
                                       bool use_directions = true) const;
  // For the summaries' scans, which read values only: At without the
  // verification, and whether some K > 0 is stable at B (the first stable
  // region found ends the search).
  CriticalPoint ValueAt(double B) const;
  bool AnyStable(double B) const;
  // StableIntervals without the verification (the scan of ScanStableB).
  std::vector<KInterval> IntervalValues(double B) const;
  // The largest K_CR that a golden-section search on [lo, hi] evaluates (and
  // where, when b_at is given).
  double LargestKcr(double lo, double hi, double tol, double* b_at) const;
  // Where no crossing has K > 0: a K at which to confirm that every K > 0 is
  // as stable as K -> 0+.
  double NoCrossingProbe(const std::vector<Crossing>& xs) const;

  // Picks IsStable's test from polynomial_error().
  void ChooseStabilityTest();
  // The B > 0 where the K = 0 boundary is crossed (sorted), and the number of
  // roots outside at K = 0+ between two of them, found once per interval
  // (eigenvalue test only): roots cross the circle at K = 0+ only there.
  std::vector<double> ZeroKCandidates(std::vector<int>* changes) const;
  int RootsOutsideAtZeroK(double B) const;
  // The count at K = 0+ of one interval of zero_k_b_ by the eigenvalues, and
  // the counts of a block of kZeroKBlock intervals from its first one and the
  // directions of the crossings between.
  int DirectZeroKCount(size_t slot) const;
  void FillZeroKBlock(size_t block) const;
  static constexpr size_t kZeroKBlock = 8;
  // Schur-Cohn on the characteristic polynomial (K = 0 as 0+).
  bool PolynomialStable(double K, double B) const;
  // Whether K_in is stable and K_out (1e-6 across a boundary from it) is
  // not: by Schur-Cohn where polynomial_error() <= kPolynomialVerifyTolerance
  // (O(n^2)), else, or where it does not confirm, by stable(K).
  // With ill-conditioned poles (count_by_crossings_) the eigenvalues decide
  // instead, at the smallest offset delta of 1e-6, 1e-5, 1e-4, 1e-3 (below
  // half of gap, the end's relative distance to its nearest other crossing)
  // at which they read stable inside and unstable outside: they cannot place
  // a root closer to the circle than the poles' conditioning allows.
  template <typename Stable>
  bool ConfirmsEnd(double K_in, double K_out, double B, const Stable& stable, double gap = 0.0) const;
  // The number of roots outside at (K > 0, B) from the crossings: the count
  // at K = 0+ (RootsOutsideAtZeroK) plus the change at every crossing below
  // K (the Nyquist count of IntervalsFrom). -1 where it is not known (a
  // crossing of unknown direction below K, K within 1e-12 of a crossing, a
  // count outside [0, order]).
  int CrossingCount(double K, double B) const;

  SampledPlant sp_;
  std::shared_ptr<const ClosedLoopMatrix> closed_loop_;
  bool use_polynomial_ = false;
  bool polynomial_verifies_ = false;  // Verify uses Schur-Cohn
  // Eigenvalue test with ill-conditioned poles (ConditioningWarning): the
  // stability of a point counts the crossings (CrossingCount), and the
  // eigenvalues only verify the ends (ConfirmsEnd). Why: with 64 sections 1 %
  // apart at damping ratio 1e-4 (eigenvalue_shift 3.4e-4) the closed loop's
  // double eigenvalues misjudge points 1e-5 (relative, in K) from K_CR(0)
  // while the crossings from the binary128 G_d place K_CR(0) within 2.4e-7
  // of the 30-digit brute force's (tests/zwidth_corner_test.cc).
  bool count_by_crossings_ = false;
  double polynomial_error_ = 0.0;
  double period_s_;
  int total_delay_;
  LoopOptions loop_;
  bool has_filter_ = false;
  // Without a hand stiffness G has its integrator pole at z = 1 (K = 0 is a
  // boundary, taken as 0+); with K_h > 0 it does not.
  bool has_integrator_ = true;
  std::vector<double> fn_ = {1.0}, fd_ = {1.0};  // F = fn/fd as polynomials in z, z^0 first
  double V_pi_ = 0.0;  // V(pi) = 2 F(-1)/T
  BoundaryOptions options_;
  std::vector<Segment> segments_;
  std::vector<double> grid_theta_, grid_K_, grid_B_;
  double K_pi_at_zero_B_ = 0.0;  // Re W(pi)
  // dW/dx and dV/dx at x = -1 on the real axis (nan when rounding hides them).
  double dW_pi_ = std::numeric_limits<double>::quiet_NaN(), dV_pi_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> zero_k_b_;  // ZeroKCandidates()
  std::vector<int> zero_k_change_;  // the change of the count at K = 0+ past each (0: unknown)
  // RootsOutsideAtZeroK per interval of zero_k_b_ (-1: not yet computed),
  // shared by copies (they share the plant and loop it depends on).
  std::shared_ptr<std::vector<std::atomic<int>>> zero_k_counts_;
};

}  // namespace zwidth::stability
