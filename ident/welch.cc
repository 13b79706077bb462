#include "ident/welch.h"
#include "ident/local_models.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>

#include <fftw3.h>

#include "ident/fft_internal.h"
#include "model/error.h"

namespace zwidth::ident {
namespace internal {

// out = w .* (x - trend), in two passes over x.
void DetrendAndWindow(Detrend d, const double* x, const double* w, double* out, int n) {
  double mean = 0.0, slope = 0.0;
  const double c = 0.5 * (n - 1);
  if (d != Detrend::kNone) {
    double sx = 0.0, sxy = 0.0;
    for (int i = 0; i < n; ++i) {
      sx += x[i];
      sxy += (i - c) * x[i];
    }
    mean = sx / n;
    if (d == Detrend::kLinear) {
      slope = sxy / (static_cast<double>(n) * (static_cast<double>(n) * n - 1.0) / 12.0);
    }
  }
  const double offset = mean - slope * c;  // trend_i = offset + slope * i
  for (int i = 0; i < n; ++i) out[i] = w[i] * (x[i] - offset - slope * i);
}

}  // namespace internal

std::string ToString(Window w) {
  switch (w) {
    case Window::kHann: return "hann";
    case Window::kHamming: return "hamming";
    case Window::kRect: return "rect";
  }
  return "?";
}
std::string ToString(Detrend d) {
  switch (d) {
    case Detrend::kNone: return "none";
    case Detrend::kMean: return "mean";
    case Detrend::kLinear: return "linear";
  }
  return "?";
}
std::string ToString(Estimator e) { return e == Estimator::kH1 ? "h1" : "h2"; }
bool FromString(const std::string& s, Window* w) {
  if (s == "hann" || s == "hanning") *w = Window::kHann;
  else if (s == "hamming") *w = Window::kHamming;
  else if (s == "rect" || s == "boxcar" || s == "rectangular") *w = Window::kRect;
  else return false;
  return true;
}
bool FromString(const std::string& s, Detrend* d) {
  if (s == "none") *d = Detrend::kNone;
  else if (s == "mean" || s == "constant") *d = Detrend::kMean;
  else if (s == "linear") *d = Detrend::kLinear;
  else return false;
  return true;
}
bool FromString(const std::string& s, Estimator* e) {
  if (s == "h1" || s == "H1") *e = Estimator::kH1;
  else if (s == "h2" || s == "H2") *e = Estimator::kH2;
  else return false;
  return true;
}

std::vector<double> MakeWindow(Window w, int n) {
  std::vector<double> out(n, 1.0);
  const double two_pi_over_n = 2.0 * std::numbers::pi / n;  // periodic: divide by n
  for (int i = 0; i < n; ++i) {
    if (w == Window::kHann) out[i] = 0.5 - 0.5 * std::cos(two_pi_over_n * i);
    if (w == Window::kHamming) out[i] = 0.54 - 0.46 * std::cos(two_pi_over_n * i);
  }
  return out;
}

int WelchOptions::overlap_samples() const {
  return static_cast<int>(std::floor(overlap * window_length));
}

WelchOptions ParseWelchOptions(const WelchOptions& numbers, const std::string& window, const std::string& detrend,
                               const std::string& estimator, bool* local) {
  WelchOptions o = numbers;
  auto shown = [](const std::string& w) { return "'" + w.substr(0, 20) + "'"; };
  if (!FromString(window, &o.window)) {
    throw InputError("WelchOptions::window " + shown(window) + " is not one of hann, hamming, rect");
  }
  if (!FromString(detrend, &o.detrend)) {
    throw InputError("WelchOptions::detrend " + shown(detrend) + " is not one of none, mean, linear");
  }
  LocalMethod method;
  const bool is_local = FromString(estimator, &method);
  if (local) *local = is_local;
  if (is_local || estimator == "robust") {  // not Welch: the Welch part keeps H1 (local: *local says so)
    o.estimator = Estimator::kH1;
  } else if (!FromString(estimator, &o.estimator)) {
    throw InputError("WelchOptions::estimator " + shown(estimator) + " is not one of h1, h2, lpm, lrm, robust");
  }
  std::string why;
  WelchOptions check = o;
  if (check.window_length == 0) check.window_length = WelchOptions{}.window_length;  // resolved per log
  if (!check.IsValid(&why)) throw InputError(why);
  return o;
}

bool WelchOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = "WelchOptions::" + m; return false; };
  if (window_length < 16) {
    return bad("window_length = " + std::to_string(window_length) + ": must be >= 16 samples");
  }
  if (window_length > (1 << 24)) return bad("window_length is over 2^24 samples");
  if (!(overlap >= 0.0 && overlap < 1.0)) {
    return bad("overlap = " + std::to_string(overlap) + ": must be in [0, 1)");
  }
  if (window_length - overlap_samples() < 1) return bad("overlap leaves no step between segments");
  if (!(std::isfinite(fmin_hz) && fmin_hz >= 0.0)) return bad("fmin_hz must be finite and >= 0");
  if (!(fmax_hz > fmin_hz)) return bad("fmax_hz must be > WelchOptions::fmin_hz");
  return true;
}

struct WelchEstimator::Fft {
  int n;
  double* in;
  fftw_complex* out_u;
  fftw_complex* out_y;
  double* in_y;
  fftw_plan plan;
  explicit Fft(int n_) : n(n_) {
    in = fftw_alloc_real(n);
    in_y = fftw_alloc_real(n);
    out_u = fftw_alloc_complex(n / 2 + 1);
    out_y = fftw_alloc_complex(n / 2 + 1);
    plan = internal::PlanCache::Get().For(n, in, out_u);
  }
  ~Fft() {
    fftw_free(in);
    fftw_free(in_y);
    fftw_free(out_u);
    fftw_free(out_y);
  }
};

WelchEstimator::WelchEstimator(const WelchOptions& options) : options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw InputError("Welch options: " + why);
  const int n = options_.window_length;
  fft_ = std::make_unique<Fft>(n);
  window_ = MakeWindow(options_.window, n);
  sw2_ = 0.0;
  for (double w : window_) sw2_ += w * w;
  // Bin correlation kappa = sum_k |c_k|^2, c_k = DFT(w^2)_k / sum(w^2), from
  // one transform of w^2 (the negative lags mirror the positive ones).
  for (int i = 0; i < n; ++i) fft_->in[i] = window_[i] * window_[i];
  fftw_execute_dft_r2c(fft_->plan, fft_->in, fft_->out_u);
  bin_correlation_ = 0.0;
  for (int k = 0; k <= n / 2; ++k) {
    const double m2 = (fft_->out_u[k][0] * fft_->out_u[k][0] + fft_->out_u[k][1] * fft_->out_u[k][1]) / (sw2_ * sw2_);
    bin_correlation_ += (k == 0 || (n % 2 == 0 && k == n / 2)) ? m2 : 2.0 * m2;
  }
  // Overlap correlations rho_j of segments j steps apart (Welch 1967).
  const int step = n - options_.overlap_samples();
  for (int j = 1; j * step < n; ++j) {
    double rho = 0.0;
    for (int i = 0; i + j * step < n; ++i) rho += window_[i] * window_[i + j * step];
    overlap_rho_.push_back(rho / sw2_);
  }
  acc_uu_.assign(n / 2 + 1, 0.0);
  acc_yy_.assign(n / 2 + 1, 0.0);
  acc_uy_.assign(n / 2 + 1, 0.0);
}

WelchEstimator::~WelchEstimator() = default;

void WelchEstimator::ProcessSegment(const double* u, const double* y) {
  const int n = options_.window_length;
  double* a = fft_->in;
  double* b = fft_->in_y;
  internal::DetrendAndWindow(options_.detrend, u, window_.data(), a, n);
  internal::DetrendAndWindow(options_.detrend, y, window_.data(), b, n);
  fftw_execute_dft_r2c(fft_->plan, a, fft_->out_u);
  fftw_execute_dft_r2c(fft_->plan, b, fft_->out_y);
  const int nb = n / 2 + 1;
  for (int k = 0; k < nb; ++k) {
    const double ur = fft_->out_u[k][0], ui = fft_->out_u[k][1];
    const double yr = fft_->out_y[k][0], yi = fft_->out_y[k][1];
    acc_uu_[k] += ur * ur + ui * ui;
    acc_yy_[k] += yr * yr + yi * yi;
    // conj(U) Y
    acc_uy_[k] += std::complex<double>(ur * yr + ui * yi, ur * yi - ui * yr);
  }
  ++segments_;
}

void WelchEstimator::Push(const double* input, const double* output, size_t count) {
  const size_t n = static_cast<size_t>(options_.window_length);
  const size_t step = n - static_cast<size_t>(options_.overlap_samples());
  const size_t chunk_begin = seen_;  // global index of input[0]
  seen_ += count;
  // Segment starts are next_start_ + j * step (global indices). buf_ holds the
  // samples from buf_begin_ to chunk_begin, always fewer than one window.
  std::vector<double> tu, ty;
  while (next_start_ + n <= seen_) {
    if (next_start_ >= chunk_begin) {
      ProcessSegment(input + (next_start_ - chunk_begin), output + (next_start_ - chunk_begin));
    } else {  // straddles the pending buffer and this chunk
      const size_t from_buf = chunk_begin - next_start_;
      const size_t off = next_start_ - buf_begin_;
      tu.assign(buf_u_.begin() + off, buf_u_.end());
      ty.assign(buf_y_.begin() + off, buf_y_.end());
      tu.insert(tu.end(), input, input + (n - from_buf));
      ty.insert(ty.end(), output, output + (n - from_buf));
      ProcessSegment(tu.data(), ty.data());
    }
    next_start_ += step;
  }
  // Keep what the next segment needs: samples from next_start_ on.
  if (next_start_ >= chunk_begin) {
    buf_u_.assign(input + std::min(next_start_ - chunk_begin, count), input + count);
    buf_y_.assign(output + std::min(next_start_ - chunk_begin, count), output + count);
  } else {
    const size_t off = next_start_ - buf_begin_;
    buf_u_.erase(buf_u_.begin(), buf_u_.begin() + off);
    buf_y_.erase(buf_y_.begin(), buf_y_.begin() + off);
    buf_u_.insert(buf_u_.end(), input, input + count);
    buf_y_.insert(buf_y_.end(), output, output + count);
  }
  buf_begin_ = std::min(next_start_, seen_);
}

FrequencyResponse WelchEstimator::Finish(double fs) const {
  const int n = options_.window_length;
  if (segments_ == 0) {
    int suggest = 16;
    while (suggest * 2 <= static_cast<int>(seen_)) suggest *= 2;
    throw InputError("the log has " + std::to_string(seen_) +
                     " samples, fewer than one window of " + std::to_string(n) +
                     (seen_ >= 16 ? "; use WelchOptions::window_length " + std::to_string(suggest) + " or less"
                                  : "; record a longer log"));
  }
  if (!(fs > 0.0) || !std::isfinite(fs)) throw InputError("sample rate must be finite and > 0");
  FrequencyResponse r;
  r.sample_rate_hz = fs;
  r.window_length = n;
  r.num_averages = segments_;
  r.estimator = options_.estimator == Estimator::kH1 ? "welch-h1" : "welch-h2";
  // Welch (1967): equivalent independent averages for overlapped segments.
  {
    double denom = 1.0;
    for (size_t j = 1; j <= overlap_rho_.size() && static_cast<int>(j) < segments_; ++j) {
      const double rho = overlap_rho_[j - 1];
      denom += 2.0 * (1.0 - static_cast<double>(j) / segments_) * rho * rho;
    }
    r.effective_averages = segments_ / denom;
    r.bin_correlation = bin_correlation_;
  }
  const double scale = 1.0 / (fs * sw2_ * segments_);
  const double df = fs / n;
  const double fmax = std::min(options_.fmax_hz, 0.5 * fs * (1.0 - 1e-12));
  const int nb = n / 2 + 1;
  const double neff = r.effective_averages;
  bool any_power = false;
  for (int k = 0; k < nb; ++k) {
    const double f = k * df;
    if (f < options_.fmin_hz - 1e-9 * df || f > fmax + 1e-9 * df) continue;
    const bool edge = (k == 0) || (n % 2 == 0 && k == n / 2);
    const double one_sided = edge ? 1.0 : 2.0;
    const double suu = acc_uu_[k] * scale * one_sided;
    const double syy = acc_yy_[k] * scale * one_sided;
    const std::complex<double> suy = acc_uy_[k] * (scale * one_sided);
    if (suu > 0.0) any_power = true;
    std::complex<double> h;
    if (options_.estimator == Estimator::kH1) h = suy / suu;
    else h = syy / std::conj(suy);
    const double coh = (suu > 0.0 && syy > 0.0) ? std::norm(suy) / (suu * syy) : 0.0;
    const double c = std::min(coh, 1.0);
    const double sd = CoherenceStd(std::abs(h), c, neff);
    r.f_hz.push_back(f);
    r.H.push_back(h);
    r.coherence.push_back(coh);
    r.H_std.push_back(sd);
    r.S_uu.push_back(suu);
    r.S_yy.push_back(syy);
    r.S_uy.push_back(suy);
  }
  if (r.f_hz.empty()) {
    throw InputError("no frequency bin between fmin and fmax (bin spacing " + std::to_string(df) +
                     " Hz); widen the band or lengthen the window");
  }
  if (!any_power) throw InputError("the input has no power in the band: constant input?");
  return r;
}

namespace {

// The power of two nearest (in ratio) to `seconds` of samples at rate_hz, in [16, 2^24].
int PowerOfTwoWindow(double rate_hz, double seconds) {
  const double e = std::isfinite(rate_hz) && rate_hz > 0 ? std::round(std::log2(rate_hz * seconds))
                                                         : std::round(std::log2(1000.0 * seconds));
  return 1 << static_cast<int>(std::clamp(e, 4.0, 24.0));
}

}  // namespace

int ShortestDefaultWindow(double rate_hz) { return PowerOfTwoWindow(rate_hz, 0.256); }

int DefaultWindowLength(double rate_hz, size_t num_samples) {
  int n = PowerOfTwoWindow(rate_hz, 4.096);
  const int shortest = ShortestDefaultWindow(rate_hz);
  while (n > shortest && 2 * static_cast<size_t>(n) > num_samples) n /= 2;
  return n;
}

bool BandOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (!(std::isfinite(fmin_hz) && fmin_hz >= 0.0)) return bad("BandOptions::fmin_hz must be finite and >= 0");
  if (!(fmax_hz > fmin_hz)) return bad("BandOptions::fmax_hz must be > BandOptions::fmin_hz");
  if (!(min_input_power_ratio >= 0.0 && min_input_power_ratio < 1.0)) {
    return bad("BandOptions::min_input_power_ratio must be in [0, 1)");
  }
  if (!(min_coherence >= 0.0 && min_coherence < 1.0)) return bad("BandOptions::min_coherence must be in [0, 1)");
  if (!(noise_coherence_sigmas >= 0.0 && std::isfinite(noise_coherence_sigmas))) {
    return bad("the band's noise_coherence_sigmas must be finite and >= 0");
  }
  if (!(well_excited_ratio >= 0.0 && well_excited_ratio <= 1.0)) return bad("the band's well_excited_ratio must be in [0, 1]");
  return true;
}

double CoherenceStd(double H_abs, double coherence, double averages) {
  const double c = std::min(coherence, 1.0);
  if (!(c > 0.0)) return std::numeric_limits<double>::infinity();
  return H_abs * std::sqrt((1.0 - c) / (2.0 * averages * c));
}

namespace {

// The mean of v over the kBandSmoothBins entries centred on each (fewer at the ends).
std::vector<double> MovingMean(const std::vector<double>& v) {
  const long n = static_cast<long>(v.size()), h = kBandSmoothBins / 2;
  std::vector<double> prefix(n + 1, 0.0), out(n);
  for (long k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + v[k];
  for (long k = 0; k < n; ++k) {
    const long a = std::max(0L, k - h), b = std::min(n, k + h + 1);
    out[k] = (prefix[b] - prefix[a]) / (b - a);
  }
  return out;
}

}  // namespace

ExcitedBand SelectExcitedBand(const FrequencyResponse& frf, const BandOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  const size_t n = frf.f_hz.size();
  ExcitedBand b;
  b.used.assign(n, 0);
  std::vector<size_t> inside_k;  // the bins of [fmin_hz, fmax_hz], ascending
  std::vector<double> inside, coherence;
  for (size_t k = 0; k < n; ++k) {
    if (!(frf.f_hz[k] >= o.fmin_hz && frf.f_hz[k] <= o.fmax_hz)) continue;
    inside_k.push_back(k);
    inside.push_back(k < frf.S_uu.size() ? frf.S_uu[k] : 0.0);
    coherence.push_back(k < frf.coherence.size() ? frf.coherence[k] : 1.0);
  }
  b.input_power_known = false;
  for (double s : inside) b.input_power_known |= s > 0.0;
  auto percentile99 = [](std::vector<double> v) {
    const size_t q = std::min(v.size() - 1, static_cast<size_t>(0.99 * v.size()));
    std::nth_element(v.begin(), v.begin() + q, v.end());
    return v[q];
  };
  if (b.input_power_known) {
    b.reference_input_psd = percentile99(inside);
    const std::vector<double> smooth = MovingMean(inside);
    const double top = percentile99(smooth);
    for (size_t i = 0; i < inside.size(); ++i) {
      const double f = frf.f_hz[inside_k[i]];
      b.smoothed_f_hz.push_back(f);
      b.smoothed_level_db.push_back(10.0 * std::log10(std::max(smooth[i], 1e-300) / top));
      if (smooth[i] >= o.well_excited_ratio * top) {
        if (b.excited_hi_hz == 0.0) b.excited_lo_hz = f;
        b.excited_hi_hz = f;
      }
    }
  }
  // Regions whose coherence is what noise alone gives (see BandOptions).
  std::vector<char> noise(inside.size(), 0);
  const double nd = frf.effective_averages;
  // The test can tell noise from a response only when its threshold (for the
  // full kBandSmoothBins) is below 0.5: from about 4 averages; fewer are judged
  // by the fit's few_averages instead.
  const double full_threshold =
      (1.0 + o.noise_coherence_sigmas * std::sqrt(std::max(1.0, frf.bin_correlation) / kBandSmoothBins)) / nd;
  // Not in closed loop (a "-joint" estimator): there the input-output coherence
  // is lowered by the loop's own path, not by a noise floor, and the estimate
  // comes from the reference (measured with the rule on: the joint fit's b
  // 3.2 std low on 1 of 5 seeds, Joint.ClosedLoopFitOfDampingIsUnbiased).
  const bool closed_loop = frf.estimator.find("joint") != std::string::npos;
  if (o.noise_coherence_sigmas > 0 && !closed_loop && nd > 1.0 && full_threshold < 0.5 && !coherence.empty()) {
    const std::vector<double> mean = MovingMean(coherence);
    const long h = kBandSmoothBins / 2, m = static_cast<long>(coherence.size());
    for (long i = 0; i < m; ++i) {
      const long count = std::min(m, i + h + 1) - std::max(0L, i - h);
      const double sd = std::sqrt(std::max(1.0, frf.bin_correlation) / count) / nd;
      noise[i] = mean[i] < 1.0 / nd + o.noise_coherence_sigmas * sd;
    }
    // Only the region that reaches the top of the band: noise sets the
    // coherence where the response has fallen below the sensor's floor, at
    // the high end. A low-coherence region below a good one is friction's
    // stick-slip or a closed loop's own path (measured with the rule applied
    // everywhere: the friction grid's b -58 %, H1's closed-loop bias hidden),
    // which the fit must see. The tail is the longest run from the top in
    // which at most 2 % of the bins look like response (chance passes).
    long edge = m, response_bins = 0;
    for (long i = m - 1; i >= 0; --i) {
      response_bins += !noise[i];
      if (noise[i] && response_bins <= 0.02 * static_cast<double>(m - i)) edge = i;
    }
    for (long i = 0; i < m; ++i) noise[i] = i >= edge;
  }
  b.num_outside = static_cast<int>(n - inside_k.size());
  for (size_t i = 0; i < inside_k.size(); ++i) {
    const size_t k = inside_k[i];
    const double f = frf.f_hz[k];
    if (b.input_power_known && !(inside[i] >= o.min_input_power_ratio * b.reference_input_psd)) {
      ++b.num_low_input;
      continue;
    }
    if (coherence[i] < o.min_coherence) { ++b.num_low_coherence; continue; }
    if (noise[i]) { ++b.num_noise_coherence; continue; }
    b.used[k] = 1;
    if (b.num_used++ == 0) b.f_lo_hz = f;
    b.f_hi_hz = f;
  }
  return b;
}

double ExcitedBand::InputLevelDb(double f_hz) const {
  if (smoothed_f_hz.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto it = std::lower_bound(smoothed_f_hz.begin(), smoothed_f_hz.end(), f_hz);
  if (it == smoothed_f_hz.begin()) return smoothed_level_db.front();
  if (it == smoothed_f_hz.end()) return smoothed_level_db.back();
  const size_t j = it - smoothed_f_hz.begin();
  const double t = (f_hz - smoothed_f_hz[j - 1]) / (smoothed_f_hz[j] - smoothed_f_hz[j - 1]);
  return smoothed_level_db[j - 1] + t * (smoothed_level_db[j] - smoothed_level_db[j - 1]);
}

std::string ExcitedBand::Describe() const {
  char s[400];
  std::snprintf(s, sizeof s, "used %d of %zu bins, %.4g-%.4g Hz", num_used, used.size(), f_lo_hz, f_hi_hz);
  std::string out = s;
  if (num_outside) out += "; " + std::to_string(num_outside) + " outside BandOptions::fmin_hz/BandOptions::fmax_hz";
  if (num_low_input) out += "; " + std::to_string(num_low_input) + " where the input carries too little power";
  if (num_low_coherence) out += "; " + std::to_string(num_low_coherence) + " with too low coherence";
  if (num_noise_coherence) {
    out += "; " + std::to_string(num_noise_coherence) + " where the coherence is what noise alone gives";
  }
  if (excited_hi_hz > 0) {
    std::snprintf(s, sizeof s, "; well excited %.4g-%.4g Hz", excited_lo_hz, excited_hi_hz);
    out += s;
  }
  if (!input_power_known) out += "; the response has no input PSD (S_uu): input power not checked";
  return out;
}

FrequencyResponse EstimateFrequencyResponse(const std::vector<double>& input,
                                            const std::vector<double>& output, double fs,
                                            const WelchOptions& options) {
  assert(input.size() == output.size());
  WelchEstimator est(options);
  est.Push(input.data(), output.data(), input.size());
  return est.Finish(fs);
}

}  // namespace zwidth::ident
