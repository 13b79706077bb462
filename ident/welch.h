// Welch-averaged spectra and the empirical frequency response of a log, as
// MATLAB's tfestimate/mscohere and SciPy's csd/welch/coherence compute them:
// periodic (DFT-even) windows, per-segment detrend, one-sided density scaling,
// mean over segments, and S_uy = E[conj(U) Y] (SciPy's convention, so a rigid
// body shows about -180 deg at low frequency).
#pragma once

#include <complex>
#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <vector>
#include "model/sample_period.h"

namespace zwidth::ident {

enum class Window { kHann, kHamming, kRect };
enum class Detrend { kNone, kMean, kLinear };
enum class Estimator { kH1, kH2 };  // H1 = S_uy/S_uu, H2 = S_yy/S_yu

std::string ToString(Window w);
std::string ToString(Detrend d);
std::string ToString(Estimator e);
bool FromString(const std::string& s, Window* w);
bool FromString(const std::string& s, Detrend* d);
bool FromString(const std::string& s, Estimator* e);

// The periodic window of length n (SciPy get_window(name, n, fftbins=True)).
std::vector<double> MakeWindow(Window w, int n);

// The default segment length for a log of n samples at rate_hz: the power of
// two nearest (in ratio) to 4.096 s of samples (a bin spacing of about 0.24 Hz
// whatever the rate: 4096 at 1 kHz, 16384 at 5 kHz, 2048 at 500 Hz), then
// halved until the log holds at least 3 segments of 50 % overlap (n >= 2 N,
// the fit's FitOptions::min_averages), and at least 16. The resolution a mode's
// bandwidth needs is in Hz, not in samples: at 5 kHz 4096 samples (0.82 s)
// bias the fitted mass by -0.3 % (2.4 std), 16384 by -0.06 %. Never below
// ShortestDefaultWindow(rate_hz): a log too short for 3 segments of that is
// refused by analysis::CheckLogLength, not estimated with a window that
// resolves nothing.
int DefaultWindowLength(double rate_hz, size_t num_samples);

// The shortest window DefaultWindowLength takes at rate_hz: the power of two
// nearest (in ratio) to 0.256 s of samples (1/16 of the default's 4.096 s:
// bins of about 3.9 Hz), and at least 16. Shorter windows leave no bin below
// the first resonance of a haptic device (tens of Hz), where the rigid body's
// mass and damping are read: a 39 ms log at 1 kHz (16-sample windows, bins of
// 62.5 Hz) was fitted to a meaningless model and reported (issue 24).
int ShortestDefaultWindow(double rate_hz);

struct WelchOptions {
  // Samples per segment, >= 16. The CLI's default is DefaultWindowLength.
  int window_length = 4096;
  double overlap = 0.5;              // fraction of a segment shared with the next, [0, 1)
  Window window = Window::kHann;
  Detrend detrend = Detrend::kLinear;
  Estimator estimator = Estimator::kH1;
  double fmin_hz = 0.7;              // band kept in the result [Hz], >= 0
  // Highest bin kept [Hz], > fmin_hz; clipped below Nyquist. The default keeps
  // every bin up to Nyquist: which of them a fit uses is decided by the input's
  // power there (SelectExcitedBand), so it follows the excitation.
  double fmax_hz = std::numeric_limits<double>::infinity();

  // The overlap in samples: floor(overlap * window_length).
  int overlap_samples() const;
  bool IsValid(std::string* why) const;
};

// The Welch options from the words a user types (the CLI's flags, Python's
// keywords; the one parser both call): window hann | hamming | rect, detrend
// none | mean | linear, estimator h1 | h2, or lpm | lrm (the local methods,
// ident/local_models.h: *local set, the estimator left h1), or robust (ident/robust_frf.h; the estimator left h1). The numbers come
// from `numbers`; window_length 0 (the front ends' default:
// DefaultWindowLength, resolved per log) is accepted. Throws InputError
// naming the field (WelchOptions::window ...) for an unknown word or a value
// out of range (WelchOptions::IsValid).
WelchOptions ParseWelchOptions(const WelchOptions& numbers, const std::string& window, const std::string& detrend,
                               const std::string& estimator, bool* local = nullptr);

struct FrequencyResponse {
  double sample_rate_hz = 0.0;
  // The sample period T = 1 / sample_rate_hz [s] of the log it was estimated
  // from: the one place it is computed (issue 24).
  double period_s() const { return model::SamplePeriod(sample_rate_hz); }
  int window_length = 0;
  int num_averages = 0;            // Welch segments averaged
  double effective_averages = 0;   // Welch (1967) equivalent independent averages
  // Variance inflation for a sum over adjacent bins: sum_k c_k^2 with c_k the
  // normalised DFT of the squared window (Hann 1.94, rect 1).
  double bin_correlation = 1.0;
  std::vector<double> f_hz;
  std::vector<std::complex<double>> H;  // output/input, e.g. rad / (N m)
  std::vector<double> coherence;        // magnitude-squared, [0, 1]
  // Standard deviation of H per bin (each of the real and imaginary parts, and
  // of |H|): Bendat & Piersol, Random Data (4th ed., sec. 9.2.4, Table 9.6),
  //   sd(H) = |H| sqrt(1 - g^2) / (|g| sqrt(2 n_d)),
  // with g^2 the coherence and n_d = effective_averages.
  std::vector<double> H_std;
  std::vector<double> S_uu, S_yy;       // one-sided PSDs [unit^2/Hz]
  std::vector<std::complex<double>> S_uy;
  // Which estimator made H: "welch-h1", "welch-h2", "welch-joint" (ident/joint.h),
  // "lpm", "lrm" (ident/local_models.h, "-joint" appended in closed loop),
  // "robust" (ident/robust_frf.h);
  // empty when unknown (a response file read back).
  std::string estimator;
  // The correlation of the errors of H at bins k and k + l, l = 1..L (index
  // l - 1): E[e_k conj(e_{k+l})] / sqrt(E|e_k|^2 E|e_{k+l}|^2), averaged over
  // the bins, as the estimator knows it (the local methods: their windows
  // overlap). Empty: unknown, the fit measures it from its residuals.
  std::vector<std::complex<double>> error_correlation;
  // The robust method (ident/robust_frf.h), per bin: the variance E|dH|^2 of
  // H from the noise, and from the nonlinear distortions (the scatter over
  // the random-phase realisations that the noise does not explain; empty
  // with one realisation). Empty for the other estimators.
  std::vector<double> noise_var, distortion_var;
  // Per bin, 1 where a fit used it (FitResult::band.used), set by the caller
  // before writing the response; empty when no fit was made.
  std::vector<char> used_by_fit;
};

// Streaming estimator: memory is a few windows whatever the log length.
class WelchEstimator {
 public:
  // Throws InputError for invalid options.
  explicit WelchEstimator(const WelchOptions& options);
  ~WelchEstimator();
  WelchEstimator(const WelchEstimator&) = delete;
  WelchEstimator& operator=(const WelchEstimator&) = delete;

  void Push(const double* input, const double* output, size_t n);
  size_t samples_seen() const { return seen_; }
  // Throws InputError when fewer samples than one window were pushed, or when
  // the input has no power in the band.
  FrequencyResponse Finish(double sample_rate_hz) const;

 private:
  void ProcessSegment(const double* u, const double* y);

  WelchOptions options_;
  struct Fft;
  std::unique_ptr<Fft> fft_;
  std::vector<double> window_;
  double sw2_ = 0.0;                 // sum of squared window
  double bin_correlation_ = 1.0;
  std::vector<double> overlap_rho_;  // rho_j for segments j steps apart
  std::vector<double> buf_u_, buf_y_;  // pending samples
  std::vector<double> acc_uu_, acc_yy_;
  std::vector<std::complex<double>> acc_uy_;
  size_t seen_ = 0;
  size_t next_start_ = 0;  // global index of the next segment's first sample
  size_t buf_begin_ = 0;   // global index of buf_u_[0]
  int segments_ = 0;
};

// Which bins of a response carry information about the device: inside
// [fmin_hz, fmax_hz], where the input has power and where the coherence is
// usable. A bin is "excited" when S_uu_k >= min_input_power_ratio * S_ref, with
// S_ref the input PSD's 99th percentile over the bins of [fmin_hz, fmax_hz] (a
// maximum that one spike cannot set). Where the input has no power the
// "response" is sensor noise, or the feedback loop's own path, even when the
// coherence stays high there.
// Coherence set by noise: with n_d independent averages the estimated
// coherence of a bin without any response is Beta(1, n_d - 1), mean 1/n_d,
// std about 1/n_d; single bins pass any fixed threshold by chance (at 5 kHz,
// hundreds of bins near Nyquist, each one a residual of several std). A bin is
// left out when the mean coherence of the kBandSmoothBins bins centred on it is
// below noise_coherence_sigmas std of that mean above 1/n_d (bins correlated as
// the window's bin_correlation says): a region where noise sets the coherence,
// not one bin of low coherence inside a good region, and only the region that
// reaches the top of the band (below a good region a low coherence is friction
// or a closed loop, not noise). Not applied when that threshold would be 0.5
// or more (about 4 averages or fewer).
// The well-excited band [excited_lo_hz, excited_hi_hz]: the bins whose input
// PSD, averaged over the kBandSmoothBins bins centred on them, is at least
// well_excited_ratio of that average's 99th percentile (half power, the
// excitation's -3 dB band). Bins outside it are used (their std says how little
// they weigh) but a section there is not supported by the data: the fit says
// so, and the order search does not add one (fit/quality.cc).
inline constexpr int kBandSmoothBins = 17;
struct BandOptions {
  double fmin_hz = 0.0;                           // lowest frequency used [Hz], >= 0
  double fmax_hz = std::numeric_limits<double>::infinity();  // highest [Hz], > fmin_hz
  double min_input_power_ratio = 1e-2;  // S_uu threshold relative to S_ref (-20 dB), in [0, 1)
  double min_coherence = 0.05;          // bins with lower coherence are left out, in [0, 1)
  // see above; >= 0 (0: the test is off). Applied only to the noise region
  // that reaches the top of the band (ident/welch.cc says why).
  double noise_coherence_sigmas = 3.0;
  double well_excited_ratio = 0.5;      // see above (-3 dB), in [0, 1]

  bool IsValid(std::string* why) const;
};

struct ExcitedBand {
  std::vector<char> used;      // per bin of the response: 1 when a fit uses it
  int num_used = 0;
  int num_outside = 0;         // outside [fmin_hz, fmax_hz]
  int num_low_input = 0;       // input power below the threshold
  int num_low_coherence = 0;   // coherence below min_coherence (counted once)
  int num_noise_coherence = 0;  // in a region whose coherence is what noise alone gives
  bool input_power_known = true;  // false when the response has no S_uu (all 0)
  double f_lo_hz = 0.0, f_hi_hz = 0.0;  // lowest and highest used bin; 0 when none
  double reference_input_psd = 0.0;     // S_ref
  // The well-excited band (see above); both 0 when the input PSD is unknown
  // (then nothing is judged outside it).
  double excited_lo_hz = 0.0, excited_hi_hz = 0.0;
  // The smoothed input PSD at f relative to the top of the band [dB] (<= 0
  // about), NaN when unknown; f between bins is interpolated, outside clamped.
  double InputLevelDb(double f_hz) const;
  std::vector<double> smoothed_f_hz, smoothed_level_db;  // the curve InputLevelDb reads
  // "used 0.7-300 Hz (1227 of 2048 bins); left out: 820 with input power 20 dB
  // below its reference (above 300.2 Hz) ...".
  std::string Describe() const;
};
// The per-bin std of H of the comment on FrequencyResponse::H_std (Bendat &
// Piersol, Random Data, 4th ed., Table 9.6): |H| sqrt((1 - g^2) / (2 n_d g^2))
// for a coherence g^2 in (0, 1] and n_d independent averages; +inf when
// g^2 <= 0. The Welch estimator and the response readers (a response made
// elsewhere that gives the coherence but no std) both use it.
double CoherenceStd(double H_abs, double coherence, double averages);

ExcitedBand SelectExcitedBand(const FrequencyResponse& frf, const BandOptions& options);

// Whole-signal convenience.
FrequencyResponse EstimateFrequencyResponse(const std::vector<double>& input,
                                            const std::vector<double>& output,
                                            double sample_rate_hz, const WelchOptions& options);

}  // namespace zwidth::ident
