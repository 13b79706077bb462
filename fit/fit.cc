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

// Delay suggested by the residual phase of the rigid body (EstimateRigid
// from the low band, start_delay taken out of its phase): H / G_rigid has
// the phase -theta D plus the sections' phase, and each section's pole pair
// and zero pair turn the phase by -180 and +180 deg, so across the band
// (both ends outside the sections) their excursions cancel. NaN when it
// cannot be read.
double ResidualPhaseDelay(const ident::FrequencyResponse& r, int start_delay) {
  const size_t n = r.f_hz.size();
  if (n < 8) return std::numeric_limits<double>::quiet_NaN();
  const model::Plant p = EstimateRigid(r, start_delay);
  model::ZohModalForm<double> g;
  g.Build(p.m, p.b, nullptr, 0, r.period_s());
  std::vector<cd> q(n);
  std::vector<double> theta(n);
  for (size_t k = 0; k < n; ++k) {
    theta[k] = kHz * r.f_hz[k] * r.period_s();
    const model::Cx<double> gk = g.At(std::cos(theta[k]), std::sin(theta[k]));
    q[k] = r.H[k] / cd(gk.re, gk.im);
  }
  // Blocks of bins averaged (q / |q| weighted by coherence, so a noisy bin
  // cannot turn a step by 2 pi), the phase unwrapped block by block, then the
  // slope between the means over the lowest and the highest tenth: the steps
  // between them all count alike, so a section's excursion cancels (a
  // weighted fit would not).
  const size_t block = std::max<size_t>(4, n / 100);
  std::vector<cd> qb;
  std::vector<double> tb;
  for (size_t k0 = 0; k0 + block <= n; k0 += block) {
    cd sum = 0.0;
    double th = 0.0;
    for (size_t k = k0; k < k0 + block; ++k) {
      sum += std::max(r.coherence[k], 1e-3) * q[k] / std::max(std::abs(q[k]), 1e-300);
      th += theta[k];
    }
    qb.push_back(sum);
    tb.push_back(th / block);
  }
  const size_t nb = qb.size();
  if (nb < 4) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> ph(nb, 0.0);
  for (size_t k = 0; k + 1 < nb; ++k) ph[k + 1] = ph[k] + std::arg(qb[k + 1] * std::conj(qb[k]));
  const size_t tenth = std::max<size_t>(1, nb / 10);
  double ph_lo = 0, ph_hi = 0, th_lo = 0, th_hi = 0;
  for (size_t k = 0; k < tenth; ++k) {
    ph_lo += ph[k]; th_lo += tb[k];
    ph_hi += ph[nb - 1 - k]; th_hi += tb[nb - 1 - k];
  }
  if (!(th_hi > th_lo) || !std::isfinite(ph_hi - ph_lo)) return std::numeric_limits<double>::quiet_NaN();
  return -(ph_hi - ph_lo) / (th_hi - th_lo);
}

double PhaseSlopeDelay(const ident::FrequencyResponse& r) {
  // The rigid body's damping is read from the phase of the low band with the
  // delay taken out: read once at delay 0, then again at the delay found.
  const double first = ResidualPhaseDelay(r, 0);
  if (!std::isfinite(first)) return first;
  return ResidualPhaseDelay(r, std::max(0, static_cast<int>(std::lround(first))));
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
  if (d < 0 || (d < static_cast<int>(sc->tried_cost.size()) && !std::isnan(sc->tried_cost[d]))) return;
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

// --delay-samples auto, after every start was screened and the best
// converged at the delay d0 that PhaseSlopeDelay suggests: the converged fit
// re-solved (warm, fully) at d0 - 1 and d0 + 1, then on in the direction that
// lowered the cost while it keeps lowering it. Costs on all bins, converged,
// decide; the starts are screened again (at the two neighbours) only when
// the fit is poor. Returns why.
std::string WalkDelay(const ident::FrequencyResponse& sub, const FitOptions& o, int n, const std::vector<model::Plant>& extra,
                      size_t usable, double suggested, bool rescreen_poor, Screening* sc, SingleFit* fin, Bins* bins,
                      int* delay) {
  const int d0 = *delay;
  int tried = 1;
  auto better = [](const SingleFit& a, const SingleFit& b) { return a.cost < b.cost; };
  // A neighbour is judged after a few iterations from the converged fit: a
  // wrong delay stays far above the right one's cost, and the right one falls
  // below a wrong one's within them.
  // The probes run on the screening's bins: the fit at the current delay is
  // probed there too, so that costs compare on the same bins.
  FitOptions probe = o;
  probe.max_iterations = std::min(o.max_iterations, 6);
  const int stride = usable > 600 ? 6 : 1;
  SingleFit here_fit;  // the probe at the current delay
  auto probe_at = [&](int d, const std::vector<double>& from) {
    const Bins coarse = MakeBins(sub, d, o.relative_std_floor, stride);
    std::vector<double> xs = from;
    return Solve(coarse, n, xs, probe);
  };
  auto solve_at = [&](const std::vector<int>& ds, const std::vector<double>& from) {
    std::vector<SingleFit> fits(ds.size());
    ParallelFor(ds.size(), [&](size_t k) { fits[k] = probe_at(ds[k], from); });
    int step = 0;
    for (size_t k = 0; k < ds.size(); ++k) {
      ++tried;
      sc->iterations += fits[k].iterations;
      if (better(fits[k], here_fit)) {
        step = ds[k] - *delay;
        here_fit = fits[k];
        *delay = ds[k];
      }
    }
    return step;
  };
  auto walk = [&] {
    here_fit = probe_at(*delay, fin->x);
    sc->iterations += here_fit.iterations;
    std::vector<int> first;
    if (*delay > 0) first.push_back(*delay - 1);
    if (*delay < o.max_auto_delay) first.push_back(*delay + 1);
    int step = solve_at(first, fin->x);
    while (step != 0 && *delay + step >= 0 && *delay + step <= o.max_auto_delay) {
      step = solve_at({*delay + step}, here_fit.x) != 0 ? step : 0;
    }
  };
  // Walks, and converges on all bins where the walk ended elsewhere.
  auto finish = [&] {
    const int before = *delay;
    walk();
    if (*delay == before) return;
    *bins = MakeBins(sub, *delay, o.relative_std_floor);
    std::vector<double> xs = here_fit.x;
    const SingleFit f = Solve(*bins, n, xs, o);
    sc->iterations += f.iterations;
    *fin = f;
  };
  finish();
  // A fit at a delay one sample off bends its sections into a minimum that
  // the warm re-solve at the right delay does not leave (at 1 kHz one sample
  // is 108 deg at 300 Hz). When the fit does not explain the response
  // (chi2/dof above Chi2PerDofLimit), every start is screened at the two
  // neighbours too, and the walk goes on from the better.
  const int dof = 2 * static_cast<int>(bins->z.size()) - (2 + 4 * n);
  const bool poor = rescreen_poor && 2.0 * fin->cost / std::max(1, dof) > Chi2PerDofLimit(dof, sub);
  bool rescreened = false;
  if (poor) {
    Screening again;
    for (int d : {*delay - 1, *delay + 1}) {
      if (d >= 0 && d <= o.max_auto_delay) ScreenDelay(sub, o, n, extra, usable, d, &again);
    }
    sc->starts_tried += again.starts_tried;
    if (again.best_delay >= 0 && std::isfinite(again.best.cost)) {
      Bins b2;
      int d2 = again.best_delay;
      const SingleFit f2 = ConvergeBest(sub, o, n, &again, &b2, &d2);
      tried += 2;
      rescreened = true;
      if (better(f2, *fin)) {
        *fin = f2;
        *bins = std::move(b2);
        *delay = d2;
        finish();
      }
    }
    sc->iterations += again.iterations;
  }
  std::ostringstream why;
  why << "delay " << *delay << " samples: the lowest cost of " << tried << " delays, the fit converged at " << d0
      << " (the residual phase of the rigid body suggested ";
  if (std::isfinite(suggested)) why << std::setprecision(3) << suggested; else why << "nothing";
  why << ") re-solved from there one sample at a time while the cost fell";
  if (rescreened) why << ", every start screened again beside the first walk's end (its fit was poor)";
  why << "; searched up to " << o.max_auto_delay;
  return why.str();
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

Fixed FitFixed(const ident::FrequencyResponse& sub, const FitOptions& o, int n, const std::vector<model::Plant>& extra,
               bool rescreen_poor) {
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
  const double suggested = o.auto_delay ? PhaseSlopeDelay(sub) : 0.0;
  const int d0 = !o.auto_delay ? o.delay_samples
                 : std::isfinite(suggested) ? std::clamp(static_cast<int>(std::lround(suggested)), 0, o.max_auto_delay)
                                            : 0;
  ScreenDelay(sub, o, n, extra, usable, d0, &sc);
  res.starts_tried = sc.starts_tried;
  if (sc.best_delay < 0 || !std::isfinite(sc.best.cost)) {
    res.iterations = sc.iterations;
    res.status = FitStatus::kNoConvergence;
    res.message = "no start produced a usable fit";
    return out;
  }
  Bins bins;
  int delay = sc.best_delay;
  SingleFit fin = ConvergeBest(sub, o, n, &sc, &bins, &delay);
  if (o.auto_delay) res.delay_choice = WalkDelay(sub, o, n, extra, usable, suggested, rescreen_poor, &sc, &fin, &bins, &delay);
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
  if (frf.num_averages < o.min_averages && !o.allow_few_averages && frf.window_length > 0 &&
      frf.window_length <= 16) {  // the shortest window: a shorter one cannot help; the log is too short
    throw InputError("the log is too short: " + std::to_string(frf.num_averages) + " Welch segment(s) of " +
                     std::to_string(frf.window_length) + " samples (the shortest window), fewer than the " +
                     std::to_string(o.min_averages) + " a per-bin std needs; record a longer log (at least " +
                     std::to_string((o.min_averages + 1) * frf.window_length / 2) +
                     " samples at 50 % overlap), or FitOptions::allow_few_averages to fit anyway (judged poor)");
  }
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
                       chosen.res.chi2_per_dof > Chi2Limit(chosen.res, sub);
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
