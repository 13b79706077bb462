// The quality verdict of a converged fit (FitResult::quality) and the
// spurious-section tests shared with the order search.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "fit/fit_internal.h"
#include "fit/friction_fit.h"

namespace zwidth::fit {
namespace internal {

std::string Fmt(const char* fmt, double a, double b, double c, double d) {
  char s[300];
  std::snprintf(s, sizeof s, fmt, a, b, c, d);
  return s;
}

double Chi2Limit(const FitResult& r, const ident::FrequencyResponse& frf) {
  return Chi2PerDofLimit(r.num_residuals - r.num_parameters, frf);
}

// Leakage of the Welch window (a tapered one: bin_correlation > 1.2; a
// whole-record response of a periodic excitation has none). The estimate is
// the response smoothed by the window's power kernel, of variance
// sigma^2 = df^2 / 3 for Hann (df the bin spacing; by Parseval,
// int w'^2 / (4 pi^2 int w^2) for w = sin^2(pi t / T_w)), which widens a peak of
// half-power bandwidth bw [Hz] by the relative amount (4/3) (df / bw)^2 (a
// Lorentzian's half-width gamma becomes gamma + sigma^2 / gamma): the fitted
// damping of that pole or zero is biased up by about as much (the fit's
// other parameters absorb part of it). A section narrower than 2 bins makes
// the fit poor; a bias bound above 3 of its std errors is a warning.
void LeakageChecks(const ident::FrequencyResponse& sub, FitResult* res) {
  if (!(sub.bin_correlation > 1.2) || sub.window_length <= 0 || !(sub.sample_rate_hz > 0)) return;
  if (!sub.error_correlation.empty()) return;  // a local method: no window, its transient removed
  const double df = sub.sample_rate_hz / sub.window_length;
  const std::vector<model::Mode>& modes = res->plant.modes;
  for (size_t i = 0; i < modes.size(); ++i) {
    const bool have_std = i < res->std_errors.modes.size();
    for (int zero = 0; zero < 2; ++zero) {
      const double w = zero ? modes[i].v : modes[i].omega, c = zero ? modes[i].d : modes[i].c;
      const double sd = have_std ? (zero ? res->std_errors.modes[i].d : res->std_errors.modes[i].c) : NAN;
      const double bw = c / (2.0 * std::numbers::pi), r = df / bw, bias = 4.0 / 3.0 * r * r;
      const double f = w / (2.0 * std::numbers::pi);
      // (r is +inf for c = 0; the exponent is kept in int range)
      const int longer = 1 << static_cast<int>(std::ceil(std::log2(std::clamp(4.0 * r, 2.0, 1e9))));
      const std::string the = std::string("the ") + (zero ? "antiresonance" : "resonance");
      if (r > 0.5) {
        res->reasons.push_back(
            {"mode_narrower_than_bins",
             the + Fmt(" at %.4g Hz is %.3g Hz wide (half power), under 2 bins of the window (%.3g Hz): its leakage "
                       "widens it, and the fitted damping is too large (by up to about %.0f %%)",
                       f, bw, df, 100.0 * bias),
             "a window " + std::to_string(longer) + " times longer (WelchOptions::window_length), or the local "
             "rational method, which has no window (LocalModelOptions::method lrm)"});
      } else if (std::isfinite(sd) && sd > 0 && bias * c > 3.0 * sd) {
        res->warnings.push_back(
            "the damping of " + the +
            Fmt(" at %.4g Hz (%.3g Hz wide) may be biased up by the window's leakage by up to %.2g %%, %.2g times "
                "its std error; a longer WelchOptions::window_length reduces it (4 times longer: 16 times less), "
                "the local rational method (LocalModelOptions::method lrm) removes it",
                f, bw, 100.0 * bias, bias * c / sd));
      }
    }
  }
}

// The robust method's split of the variance (ident/robust_frf.h): where the
// rigid body sets m and b (and K_CR scales with them, eq. (2)), the bins below
// half the lowest fitted section frequency (all bins when fewer than 5 lie
// there), a median nonlinear-distortion variance above the noise variance
// means that the response is that of a nonlinear device (friction, backlash)
// linearised at this excitation, and more averaging would not make it the
// device's: the fit is poor. For a linear device distortion_var is
// max(0, total - noise), a chance fluctuation whose median over many bins is
// about 0 (total / noise ~ chi2 with 2 (M - 1) dof over 2 (M - 1)).
void DistortionCheck(const ident::FrequencyResponse& sub, FitResult* res) {
  const size_t n = sub.f_hz.size();
  if (sub.distortion_var.size() != n || sub.noise_var.size() != n || n == 0) return;
  double lowest_hz = std::numeric_limits<double>::infinity();
  for (const model::Mode& m : res->plant.modes) lowest_hz = std::min({lowest_hz, m.omega, m.v});
  lowest_hz /= 2.0 * std::numbers::pi;
  std::vector<double> ratio;
  double hi = 0.0;
  for (int pass = 0; pass < 2 && ratio.size() < 5; ++pass) {
    ratio.clear();
    for (size_t k = 0; k < n; ++k) {
      if (pass == 0 && !(sub.f_hz[k] < 0.5 * lowest_hz)) continue;
      if (!(sub.noise_var[k] > 0.0)) continue;
      ratio.push_back(sub.distortion_var[k] / sub.noise_var[k]);
      hi = sub.f_hz[k];
    }
  }
  if (ratio.empty()) return;
  std::nth_element(ratio.begin(), ratio.begin() + ratio.size() / 2, ratio.end());
  const double median = ratio[ratio.size() / 2];
  res->distortion_to_noise = median;
  if (!(median > 1.0)) return;
  res->reasons.push_back(
      {"nonlinear_distortion",
       Fmt("the nonlinear distortion of the response is %.3g times its noise (median variance ratio over %.0f lines "
           "from %.4g to %.4g Hz, where m and b, and so K_CR, are set): the device is not linear at this excitation, "
           "and more averaging would not make the model its own",
           median, static_cast<double>(ratio.size()), sub.f_hz.front(), hi),
       "friction or backlash, not noise, limits the model: identify the friction from a time-domain log "
       "(FrictionFitOptions::model coulomb), excite harder (the distortion of friction shrinks relative to the "
       "response as the input grows), or check the device for play"});
}

// "a", "a or b", "a, b, or c": the non-empty items as alternatives of one
// advice sentence (an empty list gives "").
std::string Alternatives(const std::vector<std::string>& items) {
  std::vector<std::string> kept;
  for (const std::string& s : items) {
    if (!s.empty()) kept.push_back(s);
  }
  std::string out;
  for (size_t i = 0; i < kept.size(); ++i) {
    if (i > 0) out += kept.size() == 2 ? " or " : (i + 1 == kept.size() ? ", or " : ", ");
    out += kept[i];
  }
  return out;
}

// More modes: the order search when it was not used, else a higher limit
// (when the search reached it) or nothing (more modes were tried and lost).
std::string MoreModesAdvice(const FitOptions& o, const FitResult& r) {
  if (!o.auto_modes) return "more modes (FitOptions::auto_modes)";
  return static_cast<int>(r.plant.modes.size()) >= o.max_modes ? "more modes (FitOptions::max_modes)" : "";
}

// The quality tests (see FitResult::quality).
void JudgeQuality(const Fixed& fx, const ident::FrequencyResponse& sub, const FitOptions& o, FitResult* res) {
  auto add = [&](std::string code, std::string msg, std::string advice) {
    res->reasons.push_back({std::move(code), std::move(msg), std::move(advice)});
  };
  const double kappa = std::max(1.0, sub.bin_correlation);
  const double chi_limit = Chi2Limit(*res, sub);
  const std::string more_modes = MoreModesAdvice(o, *res);
  if (res->chi2_per_dof > chi_limit) {
    add("chi2_per_dof", Fmt("chi2/dof %.3g is above %.3g: the model does not explain the response within its std",
                            res->chi2_per_dof, chi_limit),
        "try " + Alternatives({more_modes, o.auto_delay ? "" : "FitOptions::auto_delay",
                               "a band where the device is linear (BandOptions::fmin_hz/BandOptions::fmax_hz)",
                               "check for a mode above Nyquist or aliasing (eq. 1 cannot fit one)"}));
  }
  if (Chi2SmallSampleFactor(sub) > 1.0) {
    const Chi2SmallSample law = Chi2SmallSampleLaw(sub);
    res->warnings.push_back(
        Fmt("the response's per-bin std rests on %.2g averages (segments, or runs): estimated from as few, it makes "
            "a right model's chi2/dof about %.2g, and the verdict's limit is scaled to %.3g; more averages (a longer "
            "log, or a shorter WelchOptions::window_length) make the verdict and the std firmer",
            law.n, law.expected, chi_limit));
  }
  // Runs test on every 3rd bin (Hann bins 3 apart are uncorrelated), or past
  // the correlation the estimator reports (a local method's window).
  const int stride = !sub.error_correlation.empty() ? static_cast<int>(sub.error_correlation.size()) + 1
                     : kappa > 1.2                  ? 3
                                                    : 1;
  double z_min = 0;
  for (int part = 0; part < 2; ++part) {
    int n1 = 0, n2 = 0, runs = 0, last = 0;
    for (size_t k = 0; k < fx.r.size(); k += stride) {
      const double v = part == 0 ? fx.r[k].real() : fx.r[k].imag();
      const int s = v >= 0 ? 1 : -1;
      (s > 0 ? n1 : n2)++;
      if (s != last) ++runs;
      last = s;
    }
    const double nn = n1 + n2;
    if (n1 < 2 || n2 < 2) { z_min = std::min(z_min, -10.0); continue; }
    const double mu = 2.0 * n1 * n2 / nn + 1.0;
    const double var = (mu - 1.0) * (mu - 2.0) / (nn - 1.0);
    if (var > 0) z_min = std::min(z_min, (runs - mu) / std::sqrt(var));
  }
  res->runs_z = z_min;
  if (z_min < -4.0) {
    add("residual_runs", Fmt("the residual has long runs of one sign (runs test z = %.3g < -4): systematic misfit", z_min),
        "the model misses a feature of the response: " +
            Alternatives({more_modes, o.auto_delay ? "" : "a delay (FitOptions::auto_delay)",
                          "a band that leaves it out (BandOptions::fmin_hz/BandOptions::fmax_hz)"}));
  }
  // Misfit concentrated in one octave.
  if (!fx.r.empty()) {
    const double f0 = fx.f_hz.front();
    const int nbands = std::max(1, static_cast<int>(std::ceil(std::log2(fx.f_hz.back() / f0 + 1e-12))));
    std::vector<double> s2(nbands + 1, 0.0);
    std::vector<int> cnt(nbands + 1, 0);
    double tot = 0;
    for (size_t k = 0; k < fx.r.size(); ++k) {
      const int b = std::clamp(static_cast<int>(std::floor(std::log2(fx.f_hz[k] / f0))), 0, nbands);
      s2[b] += std::norm(fx.r[k]);
      cnt[b] += 1;
      tot += std::norm(fx.r[k]);
    }
    int worst = -1;
    double worst_chi = 0, rest_chi = 0;
    for (int b = 0; b <= nbands; ++b) {
      if (cnt[b] < 8 || cnt[b] == static_cast<int>(fx.r.size())) continue;
      const double c = s2[b] / (2.0 * cnt[b]);
      const double rest = (tot - s2[b]) / (2.0 * (fx.r.size() - cnt[b]));
      if (c > 4.0 && c > 3.0 * rest && c > worst_chi) { worst = b; worst_chi = c; rest_chi = rest; }
    }
    if (worst >= 0) {
      const double a = f0 * std::exp2(worst), b = std::min(f0 * std::exp2(worst + 1), fx.f_hz.back());
      res->misfit_band_hz = {a, b};
      add("misfit_band", Fmt("the misfit is concentrated in %.4g-%.4g Hz (chi2/dof %.3g there, %.3g elsewhere)", a, b,
                             worst_chi, rest_chi),
          "a mode there is missing or wrong: more modes, or leave that band out (BandOptions::fmin_hz/BandOptions::fmax_hz)");
    }
  }
  if (sub.num_averages < o.min_averages) {
    add("few_averages", "the response averages " + std::to_string(sub.num_averages) +
                            " Welch segment(s): its per-bin std, hence the weights and the standard errors, mean little",
        "record a longer log or use a shorter WelchOptions::window_length");
  }
  LeakageChecks(sub, res);
  DistortionCheck(sub, res);
  for (const std::string& s : SpuriousSections(*res, o)) {
    const bool bound = s.find("bound") != std::string::npos;
    if (s.find("well-excited band") != std::string::npos) {
      add("section_outside_excited_band", s,
          "an excitation whose band covers that frequency, or fewer modes (FitOptions::auto_modes)");
      continue;
    }
    add(bound ? "parameter_at_bound" : "spurious_section", s,
        bound ? "the data may not support this many modes: fewer modes (FitOptions::auto_modes)"
              : "fewer modes (FitOptions::auto_modes) or a wider band");
  }
}

}  // namespace internal

using namespace internal;

std::string ToString(FitQuality q) {
  switch (q) {
    case FitQuality::kNotJudged: return "not judged";
    case FitQuality::kGood: return "good";
    case FitQuality::kPoor: return "poor";
  }
  return "?";
}

std::vector<std::string> SpuriousSections(const FitResult& r, const FitOptions& o) {
  std::vector<std::string> out;
  const model::Plant& p = r.plant;
  const double nyq_w = std::numbers::pi * r.band_sample_rate_hz;
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const std::string name = "section " + std::to_string(i + 1);
    const model::Mode& md = p.modes[i];
    // Nearest zero to this pole.
    size_t j = 0;
    for (size_t q = 1; q < p.modes.size(); ++q) {
      if (std::abs(std::log(p.modes[q].v / md.omega)) < std::abs(std::log(p.modes[j].v / md.omega))) j = q;
    }
    const model::Mode& mz = p.modes[j];
    const cd s(0.0, md.omega);
    const cd ratio = (s * s + mz.d * s + mz.v * mz.v) / (s * s + md.c * s + md.omega * md.omega);
    // Cancelled: the pair changes G by less than 5 % at the pole, or by less
    // than 50 % with the two frequencies within 2 % and within two standard
    // deviations of each other (a lightly damped pair that only fits noise).
    bool same_frequency = false;
    if (r.std_errors.modes.size() == p.modes.size()) {
      const double sw = r.std_errors.modes[i].omega, sv = r.std_errors.modes[j].v;
      same_frequency = std::abs(ratio - 1.0) < 0.5 && std::abs(md.omega - mz.v) < 0.02 * md.omega &&
                       std::abs(md.omega - mz.v) < 2.0 * std::sqrt(sw * sw + sv * sv);
    }
    if (std::abs(ratio - 1.0) < 0.05 || same_frequency) {
      out.push_back(name + Fmt(": its pole at %.4g Hz is cancelled by the zero at %.4g Hz", md.omega / kHz, mz.v / kHz));
    }
    const double zc = md.c / (2 * md.omega), zd = md.d / (2 * md.v);
    if (zc > 0.999 * o.max_pole_damping_ratio || zc < 1.001 * o.min_damping_ratio) {
      out.push_back(name + Fmt(": the pole damping ratio %.3g is at its bound", zc));
    }
    if (zd > 0.999 * o.max_zero_damping_ratio || zd < 1.001 * o.min_damping_ratio) {
      out.push_back(name + Fmt(": the zero damping ratio %.3g is at its bound", zd));
    }
    if (nyq_w > 0 && (md.omega > 0.999 * o.max_frequency_fraction * nyq_w || md.v > 0.999 * o.max_frequency_fraction * nyq_w)) {
      out.push_back(name + ": a frequency is at its bound (near Nyquist)");
    }
    if (r.std_errors.modes.size() == p.modes.size()) {
      const model::Mode& e = r.std_errors.modes[i];
      if (!(e.omega < md.omega && e.c < md.c && e.v < md.v && e.d < md.d)) {
        out.push_back(name + ": a parameter's std is larger than its value (or unknown)");
      }
    }
    if (r.band.num_used > 0) {
      const double lo = kHz * r.band.f_lo_hz / 1.05, hi = kHz * r.band.f_hi_hz * 1.05;
      if (md.omega < lo || md.omega > hi || md.v < lo || md.v > hi) {
        out.push_back(name + Fmt(": pole %.4g Hz or zero %.4g Hz is outside the used band", md.omega / kHz, md.v / kHz));
      } else if (r.band.excited_hi_hz > 0) {
        const double elo = kHz * r.band.excited_lo_hz / 1.05, ehi = kHz * r.band.excited_hi_hz * 1.05;
        const double w = (md.omega < elo || md.omega > ehi) ? md.omega : md.v;
        if (w < elo || w > ehi) {
          out.push_back(name + Fmt(": %.4g Hz lies outside the well-excited band %.4g-%.4g Hz, where the input is "
                                   "%.3g dB below its top: the data do not support a section there",
                                   w / kHz, r.band.excited_lo_hz, r.band.excited_hi_hz, -r.band.InputLevelDb(w / kHz)));
        }
      }
    }
  }
  return out;
}

}  // namespace zwidth::fit

namespace zwidth::fit {

void AddFrictionReason(const FrictionFitResult& ff, FitResult* r) {
  r->reasons.push_back(
      {"friction",
       internal::Fmt("the time-domain log shows Coulomb friction of %.3g +- %.2g (%.1f std; in the input's units): the "
                     "linear fit's damping b = %.4g takes friction's amplitude-dependent damping (4 F_c / (pi w A) at "
                     "amplitude A), so b and the Z-width depend on the drive level",
                     ff.detection_coulomb, ff.detection_coulomb_std, ff.detection_coulomb / ff.detection_coulomb_std,
                     r->plant.b),
       "fit the friction with the linear model (FrictionFitOptions::model coulomb or auto); to test, record two "
       "logs at drive levels 2-4 x apart: a linear device gives the same b at both"});
  r->quality = FitQuality::kPoor;
}

}  // namespace zwidth::fit
