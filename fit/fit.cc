#include "fit/fit.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

#include "fit/bin_correlated_covariance.h"
#include "fit/fit_internal.h"
#include "model/error.h"
#include "model/parallel.h"
#include "model/zoh_modal.h"

namespace zwidth::fit {
namespace internal {

// The bins of frf where used[k] != 0, with every per-bin vector kept aligned.
ident::FrequencyResponse Restrict(const ident::FrequencyResponse& frf, const std::vector<char>& used) {
  ident::FrequencyResponse r = frf;
  r.f_hz.clear(); r.H.clear(); r.coherence.clear(); r.H_std.clear(); r.S_uu.clear(); r.S_yy.clear(); r.S_uy.clear();
  r.noise_var.clear(); r.distortion_var.clear();
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    if (!used[k]) continue;
    r.f_hz.push_back(frf.f_hz[k]);
    r.H.push_back(frf.H[k]);
    r.coherence.push_back(k < frf.coherence.size() ? frf.coherence[k] : 1.0);
    r.H_std.push_back(frf.H_std[k]);
    if (k < frf.S_uu.size()) r.S_uu.push_back(frf.S_uu[k]);
    if (k < frf.S_yy.size()) r.S_yy.push_back(frf.S_yy[k]);
    if (k < frf.S_uy.size()) r.S_uy.push_back(frf.S_uy[k]);
    if (frf.noise_var.size() == frf.f_hz.size()) r.noise_var.push_back(frf.noise_var[k]);
    if (frf.distortion_var.size() == frf.f_hz.size()) r.distortion_var.push_back(frf.distortion_var[k]);
  }
  return r;
}

// Delay suggested by the phase slope of the upper half of the band (by
// frequency): above the rigid pole and the sections the phase of eq. (1) is
// flat (-180 deg; each section's pole and zero cancel in phase), so the slope
// is -(D + 1/2) T, the 1/2 being the ZOH's half sample. Coherence-weighted
// least squares on the unwrapped phase. NaN when it cannot be read.
double PhaseSlopeDelay(const ident::FrequencyResponse& r) {
  const size_t n = r.f_hz.size();
  if (n < 8) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> ph(n);
  ph[0] = std::arg(r.H[0]);
  for (size_t k = 1; k < n; ++k) {
    double p = std::arg(r.H[k]);
    p += 2 * std::numbers::pi * std::round((ph[k - 1] - p) / (2 * std::numbers::pi));
    ph[k] = p;
  }
  const double f_mid = 0.5 * (r.f_hz.front() + r.f_hz.back());
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < n; ++k) {
    if (r.f_hz[k] < f_mid) continue;
    const double w = std::max(r.coherence[k], 1e-3), x = kHz * r.f_hz[k];
    sw += w; sx += w * x; sy += w * ph[k]; sxx += w * x * x; sxy += w * x * ph[k];
  }
  const double den = sw * sxx - sx * sx;
  if (!(den > 0)) return std::numeric_limits<double>::quiet_NaN();
  const double slope = (sw * sxy - sx * sy) / den;
  return -slope * r.sample_rate_hz - 0.5;
}

namespace {

// The screening of starts over the delays tried: every screened start (with
// its delay) for the runners-up, and the best screened cost per delay.
struct Screening {
  std::vector<std::pair<SingleFit, int>> screened;
  std::vector<double> tried_cost;  // by delay; NaN where not tried
  SingleFit best;
  int best_delay = -1;
  int starts_tried = 0;
  int iterations = 0;
};

// Screens every start at delay d with a few iterations on every 6th bin; only
// the best go on to convergence on all bins (most of the time would
// otherwise go into starts that lose).
void ScreenDelay(const ident::FrequencyResponse& sub, const FitOptions& o, int n, const std::vector<model::Plant>& extra,
                 size_t usable, int d, Screening* sc) {
  if (d < 0 || (d < static_cast<int>(sc->tried_cost.size()) && std::isfinite(sc->tried_cost[d]))) return;
  std::vector<model::Plant> starts;
  if (o.init && static_cast<int>(o.init->modes.size()) == n) starts.push_back(*o.init);
  for (const model::Plant& s : extra) starts.push_back(s);
  for (model::Plant& s : AutomaticStarts(sub, n, d, o.max_starts)) starts.push_back(s);
  FitOptions screen = o;
  screen.max_iterations = std::min(o.max_iterations, 8);
  const Bins coarse = MakeBins(sub, d, o.relative_std_floor, usable > 600 ? 6 : 1);
  // The starts are independent: solved on their own threads, then taken in
  // order, so the outcome does not depend on timing.
  std::vector<SingleFit> fits(starts.size());
  ParallelFor(starts.size(), [&](size_t i) {
    std::vector<double> xs = ToLog(starts[i]);
    fits[i] = Solve(coarse, n, xs, screen);
  });
  double best_here = std::numeric_limits<double>::infinity();
  for (const SingleFit& f : fits) {
    ++sc->starts_tried;
    sc->iterations += f.iterations;
    best_here = std::min(best_here, f.cost);
    if (std::isfinite(f.cost)) sc->screened.push_back({f, d});
    if (f.cost < sc->best.cost) {
      sc->best = f;
      sc->best_delay = d;
    }
  }
  if (static_cast<int>(sc->tried_cost.size()) <= d) {
    sc->tried_cost.resize(d + 1, std::numeric_limits<double>::quiet_NaN());
  }
  sc->tried_cost[d] = std::isfinite(best_here) ? best_here : 1e300;
}

// --delay-samples auto: delays around the phase slope's suggestion (+-2),
// extended while the best is at an end that is not a limit. Returns why.
std::string SearchDelay(const ident::FrequencyResponse& sub, const FitOptions& o, int n,
                        const std::vector<model::Plant>& extra, size_t usable, Screening* sc) {
  const double suggested = PhaseSlopeDelay(sub);
  const int d0 = std::isfinite(suggested) ? std::clamp(static_cast<int>(std::lround(suggested)), 0, o.max_auto_delay) : 0;
  const int lo = std::max(0, d0 - 2), hi = std::min(o.max_auto_delay, d0 + 2);
  for (int d = lo; d <= hi; ++d) ScreenDelay(sub, o, n, extra, usable, d, sc);
  for (int d = hi + 1; d <= o.max_auto_delay && sc->best_delay == d - 1; ++d) ScreenDelay(sub, o, n, extra, usable, d, sc);
  for (int d = lo - 1; d >= 0 && sc->best_delay == d + 1; --d) ScreenDelay(sub, o, n, extra, usable, d, sc);
  int tlo = 0;
  while (tlo < static_cast<int>(sc->tried_cost.size()) && !std::isfinite(sc->tried_cost[tlo])) ++tlo;
  std::ostringstream why;
  why << "delay " << sc->best_delay << " samples: the lowest screened cost among " << tlo << ".."
      << sc->tried_cost.size() - 1 << " (phase slope of the upper band suggested ";
  if (std::isfinite(suggested)) why << std::setprecision(3) << suggested; else why << "nothing";
  why << "; searched up to " << o.max_auto_delay << ")";
  return why.str();
}

// Converges from the best screened point and from the runners-up whose
// screened cost is within o.runner_up_cost_ratio of it (at most
// o.max_converged_starts in all): eight iterations on a sixth of the bins do
// not always rank nearby basins right (closely spaced modes). The winner's
// bins and delay go to *bins and *delay.
SingleFit ConvergeBest(const ident::FrequencyResponse& sub, const FitOptions& o, int n, Screening* sc, Bins* bins,
                       int* delay) {
  auto& screened = sc->screened;
  std::sort(screened.begin(), screened.end(), [](const auto& a, const auto& b) { return a.first.cost < b.first.cost; });
  // The runners-up to converge are known before any is solved; they are
  // solved on their own threads and compared in order.
  std::vector<size_t> chosen;
  for (size_t i = 0; i < screened.size() && static_cast<int>(chosen.size()) < o.max_converged_starts; ++i) {
    if (i > 0 && screened[i].first.cost > o.runner_up_cost_ratio * screened[0].first.cost) break;
    chosen.push_back(i);
  }
  std::vector<Bins> here(chosen.size());
  std::vector<SingleFit> fits(chosen.size());
  ParallelFor(chosen.size(), [&](size_t k) {
    here[k] = MakeBins(sub, screened[chosen[k]].second, o.relative_std_floor);
    std::vector<double> xs = screened[chosen[k]].first.x;
    fits[k] = Solve(here[k], n, xs, o);
  });
  SingleFit fin;
  for (size_t k = 0; k < chosen.size(); ++k) {
    const SingleFit& f = fits[k];
    sc->iterations += f.iterations;
    if (k == 0 || (f.converged && !fin.converged) || (f.converged == fin.converged && f.cost < fin.cost)) {
      fin = f;
      *bins = std::move(here[k]);
      *delay = screened[chosen[k]].second;
    }
  }
  return fin;
}

// Bin positions in the frequency response (theta over the smallest spacing
// between bins), for the bins' correlation by lag.
std::vector<long> BinPositions(const Bins& bins) {
  double step = std::numeric_limits<double>::infinity();
  for (size_t k = 1; k < bins.z.size(); ++k) step = std::min(step, std::arg(bins.z[k]) - std::arg(bins.z[k - 1]));
  std::vector<long> position(bins.z.size(), 0);
  for (size_t k = 0; k < bins.z.size() && std::isfinite(step); ++k) {
    position[k] = std::lround((std::arg(bins.z[k]) - std::arg(bins.z[0])) / step);
  }
  return position;
}

// Standard errors: covariance in log space, the sandwich of
// fit/bin_correlated_covariance.h (chi2/dof times (J^T J)^-1, with the bins'
// correlation at lags 1-2 measured from the residuals where the window
// correlates neighbouring bins: bin_correlation > 1; none otherwise), then the
// delta method to (m, b, w, c, v, d). Returns that covariance in the solver's
// log space (empty when it could not be computed).
std::vector<double> StdErrors(const Bins& bins, int n, const std::vector<double>& x,
                              const ident::FrequencyResponse& sub, FitResult* res) {
  const int p = 2 + 4 * n;
  res->std_errors = res->plant;
  const double inf = std::numeric_limits<double>::infinity();
  res->std_errors.m = res->std_errors.b = inf;
  for (model::Mode& md : res->std_errors.modes) md = {inf, inf, inf, inf};
  std::vector<double> A_inv;
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  if (!LogCovariance(bins, n, x, &A_inv, &J, &r)) {
    res->warnings.push_back("the covariance could not be computed (the Jacobian is rank deficient): "
                            "some parameters are not identifiable from this response; std set to inf");
    return {};
  }
  const int max_lag = sub.bin_correlation > 1.0 + 1e-9 ? 2 : 0;
  const Eigen::Map<const Eigen::MatrixXd> A(A_inv.data(), p, p);
  // The estimator's own correlation when it knows it (the local methods), else measured.
  const Eigen::MatrixXd C = sub.error_correlation.empty()
                                ? BinCorrelatedCovariance(J, r, BinPositions(bins), A, max_lag)
                                : KnownCorrelationCovariance(J, r, BinPositions(bins), A, sub.error_correlation);
  std::vector<double> S(C.data(), C.data() + p * p);  // symmetric: row- = column-major
  auto s = [&](int i, int j) { return S[i * p + j]; };
  res->covariance_ok = true;
  res->std_errors.m = res->plant.m * std::sqrt(s(0, 0));
  res->std_errors.b = res->plant.b * std::sqrt(s(1, 1));
  for (int i = 0; i < n; ++i) {
    const int w = 2 + 4 * i, zc = 3 + 4 * i, v = 4 + 4 * i, zd = 5 + 4 * i;
    model::Mode& e = res->std_errors.modes[i];
    const model::Mode& m = res->plant.modes[i];
    e.omega = m.omega * std::sqrt(s(w, w));
    e.c = m.c * std::sqrt(std::max(0.0, s(zc, zc) + s(w, w) + 2 * s(zc, w)));
    e.v = m.v * std::sqrt(s(v, v));
    e.d = m.d * std::sqrt(std::max(0.0, s(zd, zd) + s(v, v) + 2 * s(zd, v)));
  }
  return S;
}

// Diagnostics in the measured units: the weighted residual per bin (for the
// quality tests), "fit %" (NRMSE) and the bin of the worst misfit.
void Diagnostics(const Bins& bins, Fixed* out) {
  FitResult& res = out->res;
  model::ZohModalForm<double> f;
  std::vector<double> sec;
  for (const model::Mode& md : res.plant.modes) { sec.push_back(md.omega); sec.push_back(md.c); sec.push_back(md.v); sec.push_back(md.d); }
  f.Build(res.plant.m, res.plant.b, sec.data(), static_cast<int>(res.plant.modes.size()), bins.period_s);
  cd mean = 0.0;
  for (const cd& h : bins.H) mean += h;
  mean /= static_cast<double>(bins.H.size());
  double err2 = 0, var2 = 0, worst = -1;
  size_t worst_k = 0;
  for (size_t k = 0; k < bins.z.size(); ++k) {
    const model::Cx<double> g = f.At(bins.z[k].real(), bins.z[k].imag());
    const cd model = cd(g.re, g.im) * bins.delay[k];
    err2 += std::norm(bins.H[k] - model);
    var2 += std::norm(bins.H[k] - mean);
    const cd wr = (bins.H[k] - model) * bins.weight[k];
    out->r.push_back(wr);
    out->f_hz.push_back(std::arg(bins.z[k]) / (kHz * bins.period_s));
    if (std::abs(wr) > worst) { worst = std::abs(wr); worst_k = k; }
  }
  res.nrmse_fit_percent = 100.0 * (1.0 - std::sqrt(err2 / var2));
  res.worst_misfit_hz = out->f_hz[worst_k];
}

// The solver's covariance fit_cov (sections as solved) to FitResult's
// log_covariance: (log m, log b, log omega, log c, log v, log d) with log c =
// log 2 + log zeta_c + log omega (and d alike), in canonical order.
void CanonicalCovariance(const model::Plant& as_solved, const std::vector<double>& fit_cov, FitResult* res) {
  const int n = static_cast<int>(as_solved.modes.size()), p = 2 + 4 * n;
  assert(fit_cov.size() == static_cast<size_t>(p * p));
  // Row r of A expresses output parameter r in the solver's parameters.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(p, p);
  A(0, 0) = A(1, 1) = 1.0;
  for (int i = 0; i < n; ++i) {
    int ip = 0, iz = 0;  // the solver's section holding this pole pair / zero pair
    for (int k = 0; k < n; ++k) {
      if (as_solved.modes[k].omega == res->plant.modes[i].omega) ip = k;
      if (as_solved.modes[k].v == res->plant.modes[i].v) iz = k;
    }
    A(2 + 4 * i, 2 + 4 * ip) = 1.0;
    A(3 + 4 * i, 3 + 4 * ip) = A(3 + 4 * i, 2 + 4 * ip) = 1.0;
    A(4 + 4 * i, 4 + 4 * iz) = 1.0;
    A(5 + 4 * i, 5 + 4 * iz) = A(5 + 4 * i, 4 + 4 * iz) = 1.0;
  }
  const Eigen::MatrixXd C = A * Eigen::Map<const Eigen::MatrixXd>(fit_cov.data(), p, p) * A.transpose();
  res->log_covariance.assign(C.data(), C.data() + p * p);  // symmetric: row- = column-major
}

}  // namespace

Fixed FitFixed(const ident::FrequencyResponse& sub, const FitOptions& o, int n, const std::vector<model::Plant>& extra) {
  const int p = 2 + 4 * n;
  Fixed out;
  FitResult& res = out.res;
  res.num_parameters = p;
  const size_t usable = MakeBins(sub, 0, o.relative_std_floor).z.size();
  if (static_cast<int>(2 * usable) <= p) {
    throw InputError("the response has " + std::to_string(usable) + " usable bins, too few for " +
                     std::to_string(p) + " parameters; widen BandOptions::fmin_hz/BandOptions::fmax_hz or use fewer FitOptions::num_modes");
  }
  Screening sc;
  if (!o.auto_delay) {
    ScreenDelay(sub, o, n, extra, usable, o.delay_samples, &sc);
  } else {
    res.delay_choice = SearchDelay(sub, o, n, extra, usable, &sc);
  }
  res.starts_tried = sc.starts_tried;
  if (sc.best_delay < 0 || !std::isfinite(sc.best.cost)) {
    res.iterations = sc.iterations;
    res.status = FitStatus::kNoConvergence;
    res.message = "no start produced a usable fit";
    return out;
  }
  Bins bins;
  int delay = sc.best_delay;
  const SingleFit fin = ConvergeBest(sub, o, n, &sc, &bins, &delay);
  res.iterations = sc.iterations;
  res.status = fin.converged ? FitStatus::kConverged : FitStatus::kNoConvergence;
  res.message = fin.message;
  res.cost = fin.cost;
  res.num_residuals = 2 * static_cast<int>(bins.z.size());
  res.plant = FromLog(fin.x, n);
  res.plant.delay_samples = delay;
  res.chi2_per_dof = 2.0 * res.cost / (res.num_residuals - p);
  res.std_scale = res.chi2_per_dof * std::max(1.0, sub.bin_correlation);
  const std::vector<double> fit_cov = StdErrors(bins, n, fin.x, sub, &res);
  Diagnostics(bins, &out);
  const model::Plant as_solved = res.plant;
  CanonicalOrder(&res.plant, &res.std_errors);
  if (!fit_cov.empty()) CanonicalCovariance(as_solved, fit_cov, &res);
  if (res.status != FitStatus::kConverged) res.message = "the solver did not converge: " + res.message;
  return out;
}

}  // namespace internal

using namespace internal;

void CanonicalOrder(model::Plant* plant, model::Plant* std_errors) {
  const size_t n = plant->modes.size();
  std::vector<size_t> ip(n), iz(n);
  for (size_t i = 0; i < n; ++i) ip[i] = iz[i] = i;
  std::sort(ip.begin(), ip.end(), [&](size_t a, size_t b) { return plant->modes[a].omega < plant->modes[b].omega; });
  std::sort(iz.begin(), iz.end(), [&](size_t a, size_t b) { return plant->modes[a].v < plant->modes[b].v; });
  auto apply = [&](model::Plant* p) {
    std::vector<model::Mode> m(n);
    for (size_t i = 0; i < n; ++i) {
      m[i].omega = p->modes[ip[i]].omega;
      m[i].c = p->modes[ip[i]].c;
      m[i].v = p->modes[iz[i]].v;
      m[i].d = p->modes[iz[i]].d;
    }
    p->modes = m;
  };
  apply(plant);
  if (std_errors && std_errors->modes.size() == n) apply(std_errors);
}

namespace {

// Options valid, bins and a sample rate, and enough averages for the per-bin
// std to mean something (unless o.allow_few_averages): else InputError.
void CheckInput(const ident::FrequencyResponse& frf, const FitOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  if (frf.f_hz.empty()) throw InputError("the frequency response has no bins");
  if (!(frf.sample_rate_hz > 0.0)) throw InputError("the frequency response has no sample rate");
  if (frf.num_averages < o.min_averages && !o.allow_few_averages) {
    int w = 16;
    while (w * 2 <= frf.window_length / 4) w *= 2;
    throw InputError("the response averages " + std::to_string(frf.num_averages) + " Welch segment(s) of " +
                     std::to_string(frf.window_length) + " samples; with fewer than " + std::to_string(o.min_averages) +
                     " its per-bin std, hence the fit's weights, chi2 and standard errors, mean nothing. Options: "
                     "record a longer log (at least " + std::to_string(2 * frf.window_length) +
                     " samples at this window), use a shorter window (e.g. WelchOptions::window_length " + std::to_string(w) +
                     ", at the cost of frequency resolution), or FitOptions::allow_few_averages to fit anyway (judged poor)");
  }
}

// o.num_modes sections. A fit with a spurious section may sit in a wrong
// minimum where two closely spaced modes merge and the spare section parks
// anywhere: then fit one section fewer, grow it back where its misfit peaks,
// and keep the better of the two. Only then, so the usual fit costs nothing
// more.
Fixed FitSingleOrder(const ident::FrequencyResponse& sub, const ident::ExcitedBand& band, double sample_rate_hz,
                     const FitOptions& o) {
  Fixed chosen = FitFixed(sub, o, o.num_modes, {});
  chosen.res.band = band;
  chosen.res.band_sample_rate_hz = sample_rate_hz;
  const bool suspect = chosen.res.status != FitStatus::kConverged || !SpuriousSections(chosen.res, o).empty() ||
                       chosen.res.chi2_per_dof > Chi2Limit(chosen.res, sub.bin_correlation);
  if (o.num_modes < 1 || !o.retry_spurious || !suspect) return chosen;
  FitOptions lower = o;
  lower.auto_delay = false;
  lower.delay_samples = chosen.res.plant.delay_samples;
  lower.init.reset();
  lower.max_converged_starts = std::max(o.max_converged_starts, 8);
  lower.runner_up_cost_ratio = std::max(o.runner_up_cost_ratio, 10.0);
  const Fixed prev = FitFixed(sub, lower, o.num_modes - 1, {});
  if (prev.res.status != FitStatus::kConverged) return chosen;
  Fixed again = FitFixed(sub, lower, o.num_modes, GrowStarts(prev));
  again.res.starts_tried += chosen.res.starts_tried + prev.res.starts_tried;
  again.res.iterations += chosen.res.iterations + prev.res.iterations;
  again.res.delay_choice = chosen.res.delay_choice;
  if (again.res.status == FitStatus::kConverged &&
      (chosen.res.status != FitStatus::kConverged || again.res.cost < chosen.res.cost)) {
    return again;
  }
  return chosen;
}

// Warnings about the response itself (one segment, low coherence).
void ResponseWarnings(const ident::FrequencyResponse& frf, const ident::FrequencyResponse& sub, FitResult* res) {
  if (frf.num_averages == 1) {
    res->warnings.push_back("the log gives a single Welch segment: coherence is then 1 and says nothing, "
                            "and the standard errors are not meaningful; use a longer log or a shorter window");
  }
  std::vector<double> c = sub.coherence;
  std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
  if (c[c.size() / 2] < 0.5) {
    res->warnings.push_back("coherence is below 0.5 over most of the band: the response is dominated by "
                            "noise or nonlinearity; the fit may be poor");
  }
}

// The verdict of a converged fit: the quality tests, and the searches that
// ended at their limit.
void Verdict(const Fixed& chosen, const ident::FrequencyResponse& sub, const FitOptions& o, FitResult* res) {
  JudgeQuality(chosen, sub, o, res);
  if (o.auto_modes && res->plant.modes.size() == static_cast<size_t>(o.max_modes) && o.max_modes > 0) {
    res->reasons.push_back({"order_search_at_limit",
                            "the order search chose its maximum, " + std::to_string(o.max_modes) + " modes",
                            "raise FitOptions::max_modes, or narrow the band to the modes that matter"});
  }
  if (o.auto_delay && res->plant.delay_samples >= o.max_auto_delay) {
    res->reasons.push_back({"delay_search_at_limit",
                            "the delay search chose its maximum, " + std::to_string(o.max_auto_delay) + " samples",
                            "check the log's timing (a constant input-output offset), or give FitOptions::delay_samples"});
  }
  res->quality = res->reasons.empty() ? FitQuality::kGood : FitQuality::kPoor;
}

}  // namespace

FitResult FitModel(const ident::FrequencyResponse& frf, const FitOptions& options) {
  CheckInput(frf, options);
  FitOptions o = options;
  if (!frf.error_correlation.empty()) o.relative_std_floor = options.local_relative_std_floor;
  const ident::ExcitedBand band = ident::SelectExcitedBand(frf, o.band);
  const ident::FrequencyResponse sub = Restrict(frf, band.used);
  const Fixed chosen = o.auto_modes ? FitOrders(sub, band, frf.sample_rate_hz, o)
                                    : FitSingleOrder(sub, band, frf.sample_rate_hz, o);
  FitResult res = chosen.res;
  res.band = band;
  res.band_sample_rate_hz = frf.sample_rate_hz;
  res.estimator = frf.estimator;
  ResponseWarnings(frf, sub, &res);
  if (res.status == FitStatus::kConverged) Verdict(chosen, sub, o, &res);
  return res;
}

}  // namespace zwidth::fit
