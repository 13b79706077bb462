#include "fit/fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>

#include <ceres/ceres.h>
#include <ceres/jet.h>

#include "model/error.h"
#include "model/zoh_modal.h"

namespace zwidth::fit {
namespace internal {

using cd = std::complex<double>;

// Measured data on the unit circle, prepared once per fit.
struct Bins {
  std::vector<cd> z;        // e^{j theta_k}
  std::vector<cd> delay;    // e^{-j theta_k D}
  std::vector<cd> H;
  std::vector<double> weight;  // 1 / s_k
  double period_s = 0.0;
};

// Every `stride`-th bin (stride > 1 for the cheap screening of starts).
Bins MakeBins(const ident::FrequencyResponse& frf, int delay, double floor, int stride = 1) {
  Bins b;
  b.period_s = 1.0 / frf.sample_rate_hz;
  for (size_t k = 0; k < frf.f_hz.size(); k += stride) {
    const double theta = 2.0 * std::numbers::pi * frf.f_hz[k] * b.period_s;
    double s = std::max(frf.H_std[k], floor * std::abs(frf.H[k]));
    if (!(s > 0.0) || !std::isfinite(s) || !std::isfinite(std::abs(frf.H[k]))) continue;
    b.z.push_back(std::polar(1.0, theta));
    b.delay.push_back(std::polar(1.0, -theta * delay));
    b.H.push_back(frf.H[k]);
    b.weight.push_back(1.0 / s);
  }
  return b;
}

// Physical parameters from the log-space vector x.
template <typename T>
void Physical(const T* x, int num_modes, T* m, T* b, std::vector<T>* sec) {
  using std::exp;
  *m = exp(x[0]);
  *b = exp(x[1]);
  sec->resize(4 * num_modes);
  for (int i = 0; i < num_modes; ++i) {
    const T w = exp(x[2 + 4 * i]);
    const T v = exp(x[4 + 4 * i]);
    (*sec)[4 * i] = w;
    (*sec)[4 * i + 1] = T(2.0) * exp(x[3 + 4 * i]) * w;
    (*sec)[4 * i + 2] = v;
    (*sec)[4 * i + 3] = T(2.0) * exp(x[5 + 4 * i]) * v;
  }
}

// Residuals with an analytic Jacobian per bin, built on the derivatives of the
// few pole-residue coefficients, which ceres::Jet computes (8 at a time).
class ZohResidual : public ceres::CostFunction {
 public:
  ZohResidual(const Bins* bins, int num_modes) : bins_(bins), n_(num_modes), p_(2 + 4 * num_modes) {
    set_num_residuals(2 * static_cast<int>(bins->z.size()));
    mutable_parameter_block_sizes()->push_back(p_);
  }

  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const double* x = params[0];
    const int nb = static_cast<int>(bins_->z.size());
    ZohModalForm<double> f;
    {
      double m, b;
      std::vector<double> sec;
      Physical(x, n_, &m, &b, &sec);
      if (!f.Build(m, b, sec.data(), n_, bins_->period_s)) return false;
    }
    const bool want_j = jacobians != nullptr && jacobians[0] != nullptr;
    // Gradients of each coefficient with respect to x.
    std::vector<double> dI, dea, dca;
    std::vector<cd> dE, dC;  // [mode * p_ + param]
    if (want_j) {
      dI.assign(p_, 0.0); dea.assign(p_, 0.0); dca.assign(p_, 0.0);
      dE.assign(n_ * p_, 0.0); dC.assign(n_ * p_, 0.0);
      using J = ceres::Jet<double, 8>;
      for (int s = 0; s < p_; s += 8) {
        std::vector<J> xj(p_);
        for (int q = 0; q < p_; ++q) {
          xj[q] = J(x[q]);
          if (q >= s && q < s + 8) xj[q].v[q - s] = 1.0;
        }
        J m, b;
        std::vector<J> sec;
        Physical(xj.data(), n_, &m, &b, &sec);
        ZohModalForm<J> fj;
        if (!fj.Build(m, b, sec.data(), n_, bins_->period_s)) return false;
        for (int q = s; q < std::min(p_, s + 8); ++q) {
          dI[q] = fj.integrator.v[q - s];
          dea[q] = fj.rigid_pole.v[q - s];
          dca[q] = fj.rigid_coeff.v[q - s];
          for (int i = 0; i < n_; ++i) {
            dE[i * p_ + q] = cd(fj.pole[i].re.v[q - s], fj.pole[i].im.v[q - s]);
            dC[i * p_ + q] = cd(fj.coeff[i].re.v[q - s], fj.coeff[i].im.v[q - s]);
          }
        }
      }
    }
    std::vector<cd> grad(p_);
    for (int k = 0; k < nb; ++k) {
      const cd z = bins_->z[k];
      const cd q0 = 1.0 / (z - 1.0);
      const cd qa = 1.0 / (z - f.rigid_pole);
      cd g = f.integrator * q0 + f.rigid_coeff * qa;
      if (want_j) {
        const cd ba = f.rigid_coeff * qa * qa;
        for (int q = 0; q < p_; ++q) grad[q] = dI[q] * q0 + dca[q] * qa + ba * dea[q];
      }
      for (int i = 0; i < n_; ++i) {
        const cd e(f.pole[i].re, f.pole[i].im), c(f.coeff[i].re, f.coeff[i].im);
        const cd q1 = 1.0 / (z - e), q2 = 1.0 / (z - std::conj(e));
        g += c * q1 + std::conj(c) * q2;
        if (want_j) {
          const cd b1 = c * q1 * q1, b2 = std::conj(c) * q2 * q2;
          const cd* de = &dE[i * p_];
          const cd* dc = &dC[i * p_];
          for (int q = 0; q < p_; ++q) {
            grad[q] += dc[q] * q1 + b1 * de[q] + std::conj(dc[q]) * q2 + b2 * std::conj(de[q]);
          }
        }
      }
      const double w = bins_->weight[k];
      const cd model = g * bins_->delay[k];
      const cd r = (bins_->H[k] - model) * w;
      // A non-finite value means an invalid step: say so (Ceres then shrinks
      // the step) rather than hand Ceres NaNs, which it reports at length.
      if (!std::isfinite(r.real()) || !std::isfinite(r.imag())) return false;
      residuals[2 * k] = r.real();
      residuals[2 * k + 1] = r.imag();
      if (want_j) {
        const cd scale = -w * bins_->delay[k];
        double* row_re = jacobians[0] + (2 * k) * p_;
        double* row_im = row_re + p_;
        for (int q = 0; q < p_; ++q) {
          const cd jq = scale * grad[q];
          if (!std::isfinite(jq.real()) || !std::isfinite(jq.imag())) return false;
          row_re[q] = jq.real();
          row_im[q] = jq.imag();
        }
      }
    }
    return true;
  }

 private:
  const Bins* bins_;
  int n_, p_;
};

std::vector<double> ToLog(const Plant& p) {
  std::vector<double> x = {std::log(p.m), std::log(p.b)};
  for (const Mode& md : p.modes) {
    x.push_back(std::log(md.omega));
    x.push_back(std::log(md.c / (2.0 * md.omega)));
    x.push_back(std::log(md.v));
    x.push_back(std::log(md.d / (2.0 * md.v)));
  }
  return x;
}

Plant FromLog(const std::vector<double>& x, int n) {
  Plant p;
  std::vector<double> sec;
  Physical(x.data(), n, &p.m, &p.b, &sec);
  for (int i = 0; i < n; ++i) p.modes.push_back({sec[4 * i], sec[4 * i + 1], sec[4 * i + 2], sec[4 * i + 3]});
  return p;
}

// Rigid body from the lowest 5% of the band: 1/G(jw) = -m w^2 + j b w, after
// undoing the ZOH's half-sample and the input delay's phase.
Plant EstimateRigid(const ident::FrequencyResponse& frf, int delay) {
  const double T = 1.0 / frf.sample_rate_hz;
  const double f_lo = frf.f_hz.front(), f_hi = frf.f_hz.back();
  const double limit = f_lo + 0.05 * (f_hi - f_lo);
  double sm_num = 0, sm_den = 0, sb_num = 0, sb_den = 0;
  for (size_t k = 0; k < frf.f_hz.size() && (frf.f_hz[k] <= limit || k < 4); ++k) {
    const double w = 2.0 * std::numbers::pi * frf.f_hz[k];
    const cd Y = std::polar(1.0, -w * T * (delay + 0.5)) / frf.H[k];
    const double wt = std::max(frf.coherence[k], 1e-3);
    sm_num += wt * (-Y.real()) * w * w;
    sm_den += wt * w * w * w * w;
    sb_num += wt * Y.imag() * w;
    sb_den += wt * w * w;
  }
  Plant p;
  p.m = sm_num / sm_den;
  if (!(p.m > 0.0) || !std::isfinite(p.m)) {
    // Fall back on the magnitude alone.
    const double w = 2.0 * std::numbers::pi * frf.f_hz.front();
    p.m = 1.0 / (std::abs(frf.H.front()) * w * w);
  }
  p.b = sb_num / sb_den;
  const double b_min = p.m * 2.0 * std::numbers::pi * 0.01 * std::max(f_lo, 1e-3);
  if (!(p.b > b_min) || !std::isfinite(p.b)) p.b = p.m * 2.0 * std::numbers::pi * 0.5 * f_lo;
  return p;
}

struct Extremum { size_t index; double prominence; };

// Topographic prominence of the local maxima of v.
std::vector<Extremum> Peaks(const std::vector<double>& v) {
  std::vector<Extremum> out;
  const size_t n = v.size();
  for (size_t i = 1; i + 1 < n; ++i) {
    if (!(v[i] > v[i - 1] && v[i] >= v[i + 1])) continue;
    double left_min = v[i], right_min = v[i];
    for (size_t j = i; j-- > 0;) { if (v[j] > v[i]) break; left_min = std::min(left_min, v[j]); }
    for (size_t j = i + 1; j < n; ++j) { if (v[j] > v[i]) break; right_min = std::min(right_min, v[j]); }
    out.push_back({i, v[i] - std::max(left_min, right_min)});
  }
  std::sort(out.begin(), out.end(), [](const Extremum& a, const Extremum& b) { return a.prominence > b.prominence; });
  return out;
}

}  // namespace internal

using namespace internal;

bool FitOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& m) { if (why) *why = m; return false; };
  if (num_modes < 0 || num_modes > 20) return bad("--modes must be in [0, 20]");
  if (delay_samples < 0) return bad("--delay-samples must be >= 0");
  if (max_auto_delay < 0 || max_auto_delay > 1000) return bad("max_auto_delay must be in [0, 1000]");
  if (!(min_damping_ratio > 0 && min_damping_ratio < max_pole_damping_ratio)) return bad("min_damping_ratio must be in (0, max_pole_damping_ratio)");
  if (!(max_pole_damping_ratio < 1.0)) return bad("max_pole_damping_ratio must be < 1");
  if (!(max_zero_damping_ratio > min_damping_ratio)) return bad("max_zero_damping_ratio must be > min_damping_ratio");
  if (!(max_frequency_fraction > 0 && max_frequency_fraction < 1)) return bad("max_frequency_fraction must be in (0, 1)");
  if (!(relative_std_floor >= 0)) return bad("relative_std_floor must be >= 0");
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (!(function_tolerance > 0)) return bad("function_tolerance must be > 0");
  if (max_starts < 1) return bad("max_starts must be >= 1");
  if (init && static_cast<int>(init->modes.size()) != num_modes) {
    return bad("--init has " + std::to_string(init->modes.size()) + " modes but --modes is " + std::to_string(num_modes));
  }
  return true;
}

std::string ToString(FitStatus s) {
  switch (s) {
    case FitStatus::kNotRun: return "not run";
    case FitStatus::kConverged: return "converged";
    case FitStatus::kNoConvergence: return "no convergence";
  }
  return "?";
}

void CanonicalOrder(Plant* plant, Plant* std_errors) {
  const size_t n = plant->modes.size();
  std::vector<size_t> ip(n), iz(n);
  for (size_t i = 0; i < n; ++i) ip[i] = iz[i] = i;
  std::sort(ip.begin(), ip.end(), [&](size_t a, size_t b) { return plant->modes[a].omega < plant->modes[b].omega; });
  std::sort(iz.begin(), iz.end(), [&](size_t a, size_t b) { return plant->modes[a].v < plant->modes[b].v; });
  auto apply = [&](Plant* p) {
    std::vector<Mode> m(n);
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

std::vector<Plant> AutomaticStarts(const ident::FrequencyResponse& frf, int n, int delay, int max_starts) {
  const Plant rigid = EstimateRigid(frf, delay);
  std::vector<Plant> starts;
  if (n == 0) { starts.push_back(rigid); return starts; }
  const double T = 1.0 / frf.sample_rate_hz;
  const double nyq_w = std::numbers::pi / T;
  // R = H / G_rigid,d: the sections' product, with unit gain at low frequency.
  ZohModalForm<double> rf;
  rf.Build(rigid.m, rigid.b, nullptr, 0, T);
  const size_t nb = frf.f_hz.size();
  std::vector<double> logr(nb), wgt(nb);
  for (size_t k = 0; k < nb; ++k) {
    const double theta = 2.0 * std::numbers::pi * frf.f_hz[k] * T;
    const Cx<double> g = rf.At(std::cos(theta), std::sin(theta));
    const cd gr = cd(g.re, g.im) * std::polar(1.0, -theta * delay);
    logr[k] = std::log(std::abs(frf.H[k] / gr));
    wgt[k] = std::max(frf.coherence[k], 1e-6);
  }
  // Coherence-weighted smoothing over about 1% of the band.
  const int h = std::max<int>(1, static_cast<int>(nb / 200));
  std::vector<double> sm(nb);
  for (size_t k = 0; k < nb; ++k) {
    double a = 0, w = 0;
    for (int j = -h; j <= h; ++j) {
      const long i = static_cast<long>(k) + j;
      if (i < 0 || i >= static_cast<long>(nb)) continue;
      a += wgt[i] * logr[i];
      w += wgt[i];
    }
    sm[k] = a / w;
  }
  std::vector<double> neg(nb);
  for (size_t k = 0; k < nb; ++k) neg[k] = -sm[k];
  const std::vector<Extremum> peaks = Peaks(sm), notches = Peaks(neg);
  auto omega_of = [&](size_t k) { return std::min(2.0 * std::numbers::pi * frf.f_hz[k], 0.9 * nyq_w); };
  // Candidate sets: the n most prominent, then with the next candidates swapped in.
  auto pick = [&](const std::vector<Extremum>& ex, int skip) {
    std::vector<double> w;
    for (size_t i = 0; i < ex.size() && static_cast<int>(w.size()) < n; ++i) {
      if (skip >= 0 && static_cast<int>(i) == skip && ex.size() > static_cast<size_t>(n)) continue;
      w.push_back(omega_of(ex[i].index));
    }
    // Too few extrema: spread the rest over the upper band.
    const double f_top = 2.0 * std::numbers::pi * frf.f_hz.back();
    for (int i = static_cast<int>(w.size()); i < n; ++i) w.push_back(f_top * (0.5 + 0.4 * i / std::max(1, n)));
    std::sort(w.begin(), w.end());
    return w;
  };
  auto make = [&](const std::vector<double>& wp, const std::vector<double>& wz, double zeta) {
    Plant p = rigid;
    for (int i = 0; i < n; ++i) p.modes.push_back({wp[i], 2.0 * zeta * wp[i], wz[i], 2.0 * zeta * wz[i]});
    return p;
  };
  const std::vector<double> wp = pick(peaks, -1), wz = pick(notches, -1);
  for (double zeta : {0.1, 0.03, 0.3}) starts.push_back(make(wp, wz, zeta));
  for (int s = n - 1; s >= 0 && static_cast<int>(starts.size()) < max_starts + 2; --s) {
    starts.push_back(make(pick(peaks, s), wz, 0.1));
    starts.push_back(make(wp, pick(notches, s), 0.1));
  }
  // A generic start: antiresonance just below each resonance, spread in log f.
  {
    std::vector<double> gp(n), gz(n);
    const double lo = std::log(2.0 * std::numbers::pi * std::max(frf.f_hz.front(), frf.f_hz.back() / 50));
    const double hi = std::log(2.0 * std::numbers::pi * frf.f_hz.back());
    for (int i = 0; i < n; ++i) {
      gp[i] = std::exp(lo + (hi - lo) * (i + 0.6) / n);
      gz[i] = 0.85 * gp[i];
    }
    starts.push_back(make(gp, gz, 0.1));
  }
  if (static_cast<int>(starts.size()) > max_starts) starts.resize(max_starts);
  return starts;
}

namespace {

struct SingleFit {
  bool converged = false;
  std::vector<double> x;
  double cost = std::numeric_limits<double>::infinity();
  int iterations = 0;
  std::string message;
};

// Solves from the log-space parameters x (clamped into the box, then updated
// in place) on a problem the caller owns, so that it can ask for the
// covariance afterwards.
SingleFit Solve(const Bins& bins, int n, std::vector<double>& xs, const FitOptions& o,
                ceres::Problem& problem) {
  SingleFit out;
  const double nyq_w = std::numbers::pi / bins.period_s;
  const double w_hi = std::log(o.max_frequency_fraction * nyq_w);
  const double w_lo = std::log(2.0 * std::numbers::pi * 1e-3);
  // Clamp the start into the box.
  for (int i = 0; i < n; ++i) {
    auto clamp = [&](int idx, double lo, double hi) { xs[idx] = std::min(std::max(xs[idx], lo + 1e-9), hi - 1e-9); };
    clamp(2 + 4 * i, w_lo, w_hi);
    clamp(3 + 4 * i, std::log(o.min_damping_ratio), std::log(o.max_pole_damping_ratio));
    clamp(4 + 4 * i, w_lo, w_hi);
    clamp(5 + 4 * i, std::log(o.min_damping_ratio), std::log(o.max_zero_damping_ratio));
  }
  problem.AddResidualBlock(new ZohResidual(&bins, n), nullptr, xs.data());
  for (int i = 0; i < n; ++i) {
    problem.SetParameterLowerBound(xs.data(), 2 + 4 * i, w_lo);
    problem.SetParameterUpperBound(xs.data(), 2 + 4 * i, w_hi);
    problem.SetParameterLowerBound(xs.data(), 3 + 4 * i, std::log(o.min_damping_ratio));
    problem.SetParameterUpperBound(xs.data(), 3 + 4 * i, std::log(o.max_pole_damping_ratio));
    problem.SetParameterLowerBound(xs.data(), 4 + 4 * i, w_lo);
    problem.SetParameterUpperBound(xs.data(), 4 + 4 * i, w_hi);
    problem.SetParameterLowerBound(xs.data(), 5 + 4 * i, std::log(o.min_damping_ratio));
    problem.SetParameterUpperBound(xs.data(), 5 + 4 * i, std::log(o.max_zero_damping_ratio));
  }
  // m and b within a factor e^8 (~3000) of the start: wide, but it keeps a wild
  // step of a bad start from overflowing exp().
  for (int i = 0; i < 2; ++i) {
    problem.SetParameterLowerBound(xs.data(), i, xs[i] - 8.0);
    problem.SetParameterUpperBound(xs.data(), i, xs[i] + 8.0);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // 10-30 columns: J^T J is small
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = o.function_tolerance;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-9;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary sum;
  ceres::Solve(so, &problem, &sum);
  out.converged = sum.termination_type == ceres::CONVERGENCE && sum.IsSolutionUsable();
  out.cost = sum.final_cost;
  out.iterations = static_cast<int>(sum.iterations.size());
  out.message = sum.message;
  out.x = xs;
  return out;
}

}  // namespace

FitResult FitModel(const ident::FrequencyResponse& frf, const FitOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  if (frf.f_hz.empty()) throw InputError("the frequency response has no bins");
  if (!(frf.sample_rate_hz > 0.0)) throw InputError("the frequency response has no sample rate");
  const int n = o.num_modes;
  const int p = 2 + 4 * n;
  FitResult res;
  res.num_parameters = p;
  if (frf.num_averages == 1) {
    res.warnings.push_back("the log gives a single Welch segment: coherence is then 1 and says nothing, "
                           "and the standard errors are not meaningful; use a longer log or a shorter window");
  }
  {
    std::vector<double> c = frf.coherence;
    std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
    if (c[c.size() / 2] < 0.5) {
      res.warnings.push_back("coherence is below 0.5 over most of the band: the response is dominated by "
                             "noise or nonlinearity; the fit may be poor");
    }
  }
  std::vector<int> delays;
  if (o.auto_delay) for (int d = 0; d <= o.max_auto_delay; ++d) delays.push_back(d);
  else delays.push_back(o.delay_samples);

  // Which bins are usable does not depend on the delay.
  const size_t usable = MakeBins(frf, 0, o.relative_std_floor).z.size();
  if (static_cast<int>(2 * usable) <= p) {
    throw InputError("the response has " + std::to_string(usable) + " usable bins, too few for " +
                     std::to_string(p) + " parameters; widen --fmin/--fmax or use fewer --modes");
  }
  int best_delay = -1;
  SingleFit best;
  for (int d : delays) {
    std::vector<Plant> starts;
    if (o.init) starts.push_back(*o.init);
    for (Plant& s : AutomaticStarts(frf, n, d, o.max_starts)) starts.push_back(s);
    // Screen every start with a few iterations on every 6th bin; only the
    // best goes on to convergence on all bins below (most of the time would
    // otherwise go into starts that lose).
    FitOptions screen = o;
    screen.max_iterations = std::min(o.max_iterations, 8);
    const Bins coarse = MakeBins(frf, d, o.relative_std_floor, usable > 600 ? 6 : 1);
    for (const Plant& s : starts) {
      ++res.starts_tried;
      std::vector<double> xs = ToLog(s);
      ceres::Problem screen_problem;
      const SingleFit f = Solve(coarse, n, xs, screen, screen_problem);
      res.iterations += f.iterations;
      if (f.cost < best.cost) {
        best = f;
        best_delay = d;
      }
    }
  }
  if (best_delay < 0 || !std::isfinite(best.cost)) {
    res.status = FitStatus::kNoConvergence;
    res.message = "no start produced a usable fit";
    return res;
  }
  // Converge from the best screened point, holding the problem for the covariance.
  const Bins bins = MakeBins(frf, best_delay, o.relative_std_floor);
  ceres::Problem problem;
  std::vector<double> x = best.x;
  const SingleFit fin = Solve(bins, n, x, o, problem);
  res.iterations += fin.iterations;
  res.status = fin.converged ? FitStatus::kConverged : FitStatus::kNoConvergence;
  res.message = fin.message;
  res.cost = fin.cost;
  res.num_residuals = 2 * static_cast<int>(bins.z.size());
  res.plant = FromLog(x, n);
  res.plant.delay_samples = best_delay;
  const int dof = res.num_residuals - p;
  res.chi2_per_dof = 2.0 * res.cost / dof;
  res.std_scale = res.chi2_per_dof * std::max(1.0, frf.bin_correlation);

  // Standard errors: Ceres covariance in log space, scaled, then the delta
  // method to (m, b, w, c, v, d).
  res.std_errors = res.plant;
  const double inf = std::numeric_limits<double>::infinity();
  res.std_errors.m = res.std_errors.b = inf;
  for (Mode& md : res.std_errors.modes) md = {inf, inf, inf, inf};
  std::vector<double> fit_cov;  // scaled, in the solver's log space
  {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.null_space_rank = 0;
    co.min_reciprocal_condition_number = 1e-14;
    ceres::Covariance cov(co);
    std::vector<std::pair<const double*, const double*>> blocks = {{x.data(), x.data()}};
    if (cov.Compute(blocks, &problem)) {
      std::vector<double> S(p * p);
      cov.GetCovarianceBlock(x.data(), x.data(), S.data());
      auto s = [&](int i, int j) { return S[i * p + j] * res.std_scale; };
      res.covariance_ok = true;
      fit_cov.resize(S.size());
      for (size_t k = 0; k < S.size(); ++k) fit_cov[k] = S[k] * res.std_scale;
      res.std_errors.m = res.plant.m * std::sqrt(s(0, 0));
      res.std_errors.b = res.plant.b * std::sqrt(s(1, 1));
      for (int i = 0; i < n; ++i) {
        const int w = 2 + 4 * i, zc = 3 + 4 * i, v = 4 + 4 * i, zd = 5 + 4 * i;
        Mode& e = res.std_errors.modes[i];
        const Mode& m = res.plant.modes[i];
        e.omega = m.omega * std::sqrt(s(w, w));
        e.c = m.c * std::sqrt(std::max(0.0, s(zc, zc) + s(w, w) + 2 * s(zc, w)));
        e.v = m.v * std::sqrt(s(v, v));
        e.d = m.d * std::sqrt(std::max(0.0, s(zd, zd) + s(v, v) + 2 * s(zd, v)));
      }
    } else {
      res.warnings.push_back("the covariance could not be computed (the Jacobian is rank deficient): "
                             "some parameters are not identifiable from this response; std set to inf");
    }
  }
  // Bounds reached?
  for (int i = 0; i < n; ++i) {
    const double zc = std::exp(x[3 + 4 * i]), zd = std::exp(x[5 + 4 * i]);
    if (zc > 0.999 * o.max_pole_damping_ratio || zc < 1.001 * o.min_damping_ratio ||
        zd > 0.999 * o.max_zero_damping_ratio || zd < 1.001 * o.min_damping_ratio) {
      res.warnings.push_back("section " + std::to_string(i) + " has a damping ratio at its bound: "
                             "the data may not support " + std::to_string(n) + " modes");
    }
  }
  // Diagnostics in the measured units.
  {
    ZohModalForm<double> f;
    std::vector<double> sec;
    for (const Mode& md : res.plant.modes) { sec.push_back(md.omega); sec.push_back(md.c); sec.push_back(md.v); sec.push_back(md.d); }
    f.Build(res.plant.m, res.plant.b, sec.data(), n, bins.period_s);
    cd mean = 0.0;
    for (const cd& h : bins.H) mean += h;
    mean /= static_cast<double>(bins.H.size());
    double err2 = 0, var2 = 0, worst = -1;
    size_t worst_k = 0;
    for (size_t k = 0; k < bins.z.size(); ++k) {
      const Cx<double> g = f.At(bins.z[k].real(), bins.z[k].imag());
      const cd model = cd(g.re, g.im) * bins.delay[k];
      err2 += std::norm(bins.H[k] - model);
      var2 += std::norm(bins.H[k] - mean);
      const double wr = std::abs(bins.H[k] - model) * bins.weight[k];
      if (wr > worst) { worst = wr; worst_k = k; }
    }
    res.nrmse_fit_percent = 100.0 * (1.0 - std::sqrt(err2 / var2));
    res.worst_misfit_hz = std::arg(bins.z[worst_k]) / (2.0 * std::numbers::pi * bins.period_s);
  }
  const Plant before_order = res.plant;
  CanonicalOrder(&res.plant, &res.std_errors);
  if (!fit_cov.empty()) {
    // To (log m, log b, log omega, log c, log v, log d) with log c = log 2 +
    // log zeta_c + log omega (and d alike), in canonical order: row r of A
    // expresses output parameter r in the solver's parameters.
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(p, p);
    A(0, 0) = A(1, 1) = 1.0;
    for (int i = 0; i < n; ++i) {
      int ip = 0, iz = 0;  // the solver's section holding this pole pair / zero pair
      for (int k = 0; k < n; ++k) {
        if (before_order.modes[k].omega == res.plant.modes[i].omega) ip = k;
        if (before_order.modes[k].v == res.plant.modes[i].v) iz = k;
      }
      A(2 + 4 * i, 2 + 4 * ip) = 1.0;
      A(3 + 4 * i, 3 + 4 * ip) = A(3 + 4 * i, 2 + 4 * ip) = 1.0;
      A(4 + 4 * i, 4 + 4 * iz) = 1.0;
      A(5 + 4 * i, 5 + 4 * iz) = A(5 + 4 * i, 4 + 4 * iz) = 1.0;
    }
    const Eigen::MatrixXd C = A * Eigen::Map<const Eigen::MatrixXd>(fit_cov.data(), p, p) * A.transpose();
    res.log_covariance.assign(C.data(), C.data() + p * p);  // symmetric: row- = column-major
  }
  if (res.status != FitStatus::kConverged) res.message = "the solver did not converge: " + res.message;
  return res;
}

std::string FitResult::BriefReport() const {
  std::ostringstream os;
  os << "fit " << ToString(status) << ": chi2/dof " << chi2_per_dof << ", fit " << nrmse_fit_percent
     << "%, worst misfit at " << worst_misfit_hz << " Hz, " << starts_tried << " starts, " << iterations
     << " iterations";
  return os.str();
}

}  // namespace zwidth::fit
