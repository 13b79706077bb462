#include "fit/fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <iomanip>
#include <memory>
#include <numbers>
#include <sstream>

#include <ceres/ceres.h>
#include <ceres/jet.h>
#include <Eigen/Dense>

#include "model/error.h"
#include "model/zoh_modal.h"

namespace zwidth::fit {
namespace internal {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

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

  // Ceres' bounded trust region evaluates each accepted point three times
  // (cost and gradient in its projected line search, cost as the candidate,
  // then cost and Jacobian once accepted): the last evaluation is kept and
  // reused when x is bitwise the same.
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const double* x = params[0];
    const bool want_jac = jacobians != nullptr && jacobians[0] != nullptr;
    const size_t nr = 2 * bins_->z.size();
    if (cache_valid_ && std::equal(x, x + p_, cache_x_.begin()) && (!want_jac || cache_has_jac_)) {
      if (!cache_ok_) return false;
      std::copy(cache_r_.begin(), cache_r_.end(), residuals);
      if (want_jac) std::copy(cache_j_.begin(), cache_j_.end(), jacobians[0]);
      return true;
    }
    cache_x_.assign(x, x + p_);
    cache_has_jac_ = want_jac;
    cache_ok_ = EvaluateUncached(x, residuals, want_jac ? jacobians[0] : nullptr);
    cache_valid_ = true;
    if (cache_ok_) {
      cache_r_.assign(residuals, residuals + nr);
      if (want_jac) cache_j_.assign(jacobians[0], jacobians[0] + nr * p_);
    }
    return cache_ok_;
  }

 private:
  bool EvaluateUncached(const double* x, double* residuals, double* jacobian) const {
    const int nb = static_cast<int>(bins_->z.size());
    ZohModalForm<double> f;
    {
      double m, b;
      std::vector<double> sec;
      Physical(x, n_, &m, &b, &sec);
      if (!f.Build(m, b, sec.data(), n_, bins_->period_s)) return false;
    }
    const bool want_j = jacobian != nullptr;
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
        double* row_re = jacobian + (2 * k) * p_;
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

  const Bins* bins_;
  int n_, p_;
  mutable bool cache_valid_ = false, cache_has_jac_ = false, cache_ok_ = false;
  mutable std::vector<double> cache_x_, cache_r_, cache_j_;
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
  if (max_auto_delay < 0 || max_auto_delay > 1000) return bad("max_auto_delay (--max-delay) must be in [0, 1000]");
  if (!(min_damping_ratio > 0 && min_damping_ratio < max_pole_damping_ratio)) return bad("min_damping_ratio must be in (0, max_pole_damping_ratio)");
  if (!(max_pole_damping_ratio < 1.0)) return bad("max_pole_damping_ratio must be < 1");
  if (!(max_zero_damping_ratio > min_damping_ratio)) return bad("max_zero_damping_ratio must be > min_damping_ratio");
  if (!(max_frequency_fraction > 0 && max_frequency_fraction < 1)) return bad("max_frequency_fraction must be in (0, 1)");
  if (!(relative_std_floor >= 0)) return bad("relative_std_floor must be >= 0");
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (!(function_tolerance > 0)) return bad("function_tolerance must be > 0");
  if (max_starts < 1) return bad("max_starts must be >= 1");
  if (max_modes < 0 || max_modes > 8) return bad("max_modes (--max-modes) must be in [0, 8]");
  if (min_averages < 1) return bad("min_averages must be >= 1");
  if (max_converged_starts < 1) return bad("max_converged_starts must be >= 1");
  if (!(runner_up_cost_ratio >= 1.0)) return bad("runner_up_cost_ratio must be >= 1");
  if (std::string w; !band.IsValid(&w)) return bad(w);
  if (!auto_modes && init && static_cast<int>(init->modes.size()) != num_modes) {
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

namespace internal {

// Roots of the real polynomial sum_i a[i] x^i (a.back() != 0), from the
// eigenvalues of its companion matrix.
std::vector<cd> Roots(const std::vector<double>& a) {
  const int deg = static_cast<int>(a.size()) - 1;
  if (deg < 1) return {};
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(deg, deg);
  for (int i = 1; i < deg; ++i) C(i, i - 1) = 1.0;
  for (int i = 0; i < deg; ++i) C(i, deg - 1) = -a[i] / a[deg];
  Eigen::EigenSolver<Eigen::MatrixXd> es(C, false);
  std::vector<cd> r(deg);
  for (int i = 0; i < deg; ++i) r[i] = es.eigenvalues()[i];
  return r;
}

// Second-order factors (s^2 + 2 zeta w s + w^2) from roots: complex pairs
// directly, the real roots paired in order (an overdamped factor).
std::vector<std::pair<double, double>> Quadratics(std::vector<cd> r) {
  std::vector<std::pair<double, double>> q;  // (w, 2 zeta w)
  std::vector<double> real;
  for (const cd& x : r) {
    if (std::abs(x.imag()) > 1e-9 * std::abs(x)) {
      if (x.imag() > 0) q.push_back({std::abs(x), -2.0 * x.real()});
    } else {
      real.push_back(x.real());
    }
  }
  std::sort(real.begin(), real.end());
  for (size_t i = 0; i + 1 < real.size(); i += 2) {
    q.push_back({std::sqrt(std::abs(real[i] * real[i + 1])), -(real[i] + real[i + 1])});
  }
  return q;
}

}  // namespace internal

std::optional<Plant> LinearRationalStart(const ident::FrequencyResponse& frf, int n, int delay, int iterations) {
  const size_t nb = frf.f_hz.size();
  const int dd = 2 * n + 1;  // D'(s) monic of degree 2n + 1, N(s) of degree 2n
  const int unknowns = dd + 2 * n + 1;
  if (n < 1 || static_cast<int>(2 * nb) <= unknowns + 4) return std::nullopt;
  const double T = 1.0 / frf.sample_rate_hz;
  const double w0 = kTwoPi * frf.f_hz.back();
  auto weight = [&](size_t k) {  // 1 / (w s_k): F = s H below has std w s_k
    const double s = std::max(frf.H_std[k], 1e-3 * std::abs(frf.H[k]));
    return (s > 0 && std::isfinite(s)) ? 1.0 / (kTwoPi * frf.f_hz[k] * s) : 0.0;
  };
  // F = s H with the delay and the ZOH's half sample taken out: a strictly
  // proper rational N / D' in sigma = s / w0.
  std::vector<cd> F(nb), sig(nb);
  std::vector<double> wt(nb);
  for (size_t k = 0; k < nb; ++k) {
    const double w = kTwoPi * frf.f_hz[k];
    sig[k] = cd(0.0, w / w0);
    F[k] = cd(0.0, w) * frf.H[k] * std::polar(1.0, w * T * (delay + 0.5));
    wt[k] = weight(k);
  }
  std::vector<double> den_prev(dd + 1, 0.0);
  den_prev[0] = 1.0;  // first pass: D'_prev = 1
  bool first = true;
  std::vector<double> num(2 * n + 1), den(dd + 1);
  Eigen::MatrixXd A(2 * nb, unknowns);
  Eigen::VectorXd rhs(2 * nb);
  for (int it = 0; it < iterations; ++it) {
    for (size_t k = 0; k < nb; ++k) {
      cd dp = 1.0;
      if (!first) {
        dp = 0.0;
        for (int i = dd; i >= 0; --i) dp = dp * sig[k] + den_prev[i];
      }
      const double w = wt[k] / std::max(std::abs(dp), 1e-300);
      cd p = 1.0;
      // N(sigma) - F (a_0 + ... + a_{dd-1} sigma^{dd-1}) = F sigma^dd
      for (int i = 0; i <= 2 * n; ++i) {
        A(2 * k, i) = w * p.real();
        A(2 * k + 1, i) = w * p.imag();
        p *= sig[k];
      }
      p = 1.0;
      for (int i = 0; i < dd; ++i) {
        const cd c = -F[k] * p * w;
        A(2 * k, 2 * n + 1 + i) = c.real();
        A(2 * k + 1, 2 * n + 1 + i) = c.imag();
        p *= sig[k];
      }
      const cd r = F[k] * p * w;  // p = sigma^dd
      rhs(2 * k) = r.real();
      rhs(2 * k + 1) = r.imag();
    }
    Eigen::VectorXd colscale = A.colwise().norm();
    for (int j = 0; j < unknowns; ++j) if (!(colscale(j) > 0)) colscale(j) = 1.0;
    const Eigen::MatrixXd As = A * colscale.cwiseInverse().asDiagonal();
    const Eigen::VectorXd sol = As.colPivHouseholderQr().solve(rhs).cwiseQuotient(colscale);
    if (!sol.allFinite()) return std::nullopt;
    for (int i = 0; i <= 2 * n; ++i) num[i] = sol(i);
    for (int i = 0; i < dd; ++i) den[i] = sol(2 * n + 1 + i);
    den[dd] = 1.0;
    den_prev = den;
    first = false;
  }
  // Poles: the real root nearest 0 is the rigid pole -b/m; the rest pair up.
  std::vector<cd> poles = Roots(den), zeros = Roots(num);
  if (num[2 * n] == 0.0 || poles.empty()) return std::nullopt;
  size_t ia = poles.size();
  for (size_t i = 0; i < poles.size(); ++i) {
    if (std::abs(poles[i].imag()) > 1e-9 * std::abs(poles[i])) continue;
    if (ia == poles.size() || std::abs(poles[i]) < std::abs(poles[ia])) ia = i;
  }
  if (ia == poles.size()) return std::nullopt;
  const double a = -poles[ia].real() * w0;
  poles.erase(poles.begin() + ia);
  auto qp = Quadratics(poles), qz = Quadratics(zeros);
  if (static_cast<int>(qp.size()) != n || static_cast<int>(qz.size()) != n) return std::nullopt;
  Plant p;
  p.m = 1.0;
  p.b = std::max(std::abs(a), 1e-3);
  for (int i = 0; i < n; ++i) {
    p.modes.push_back({qp[i].first * w0, std::max(std::abs(qp[i].second), 1e-6) * w0, qz[i].first * w0,
                       std::max(std::abs(qz[i].second), 1e-6) * w0});
  }
  CanonicalOrder(&p, nullptr);
  // 1 / m by weighted least squares on H = G_1 / m (G_1: this shape with m = 1).
  double num_m = 0, den_m = 0;
  for (size_t k = 0; k < nb; ++k) {
    const double w = kTwoPi * frf.f_hz[k];
    const cd g1 = ContinuousResponse(p, w) * std::polar(1.0, -w * T * (delay + 0.5));
    const double q = weight(k) * w;
    num_m += q * q * (std::conj(g1) * frf.H[k]).real();
    den_m += q * q * std::norm(g1);
  }
  const double inv_m = num_m / den_m;
  if (!(inv_m > 0) || !std::isfinite(inv_m)) return std::nullopt;
  p.m = 1.0 / inv_m;
  p.b *= p.m;
  std::string why;
  if (!p.IsValid(&why)) return std::nullopt;
  return p;
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
  starts.push_back(make(wp, wz, 0.1));
  // Second: the linear rational (Sanathanan-Koerner) fit converted to eq. (1),
  // which does not depend on spotting peaks that closely spaced or interlaced
  // modes hide. It takes the place of the last peak-swap start.
  if (max_starts > 1) {
    if (std::optional<Plant> sk = LinearRationalStart(frf, n, delay)) starts.push_back(*sk);
  }
  for (double zeta : {0.03, 0.3}) starts.push_back(make(wp, wz, zeta));
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

// (J^T J)^-1 of the weighted residual at x, row-major p x p, as Ceres'
// DENSE_SVD covariance computes it (null_space_rank 0: refused when
// (sigma_min / sigma_max)^2 < 1e-14), but from the SVD of R of J = QR (p x p)
// instead of the SVD of the tall J with its thin U: J and R have the same
// singular values and right vectors. false when J is near rank deficient or
// cannot be evaluated.
bool LogCovariance(const Bins& bins, int n, const std::vector<double>& x, std::vector<double>* cov) {
  const int p = 2 + 4 * n;
  const int rows = 2 * static_cast<int>(bins.z.size());
  if (rows < p) return false;
  const ZohResidual cost(&bins, n);
  std::vector<double> residuals(rows);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(rows, p);
  const double* params[] = {x.data()};
  double* jacobians[] = {J.data()};
  if (!cost.Evaluate(params, residuals.data(), jacobians)) return false;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullV);
  const Eigen::VectorXd sv = svd.singularValues();
  if (!(sv(0) > 0) || !sv.allFinite()) return false;
  const double ratio = sv(p - 1) / sv(0);
  if (ratio * ratio < 1e-14) return false;
  const Eigen::MatrixXd C = svd.matrixV() * sv.cwiseAbs2().cwiseInverse().asDiagonal() * svd.matrixV().transpose();
  cov->assign(C.data(), C.data() + p * p);  // symmetric: row- = column-major
  return true;
}

struct SingleFit {
  bool converged = false;
  std::vector<double> x;
  double cost = std::numeric_limits<double>::infinity();
  int iterations = 0;
  std::string message;
};

// Solves from the log-space parameters xs (clamped into the box, then updated
// in place).
SingleFit Solve(const Bins& bins, int n, std::vector<double>& xs, const FitOptions& o) {
  SingleFit out;
  ceres::Problem problem;
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
  // The projected line search that bounds bring (every step) needs no
  // gradient with quadratic interpolation: one Jacobian per iteration, not two.
  so.line_search_interpolation_type = ceres::CUBIC;
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

namespace {

constexpr double kHz = 2.0 * std::numbers::pi;

// The bins of frf where used[k] != 0, with every per-bin vector kept aligned.
ident::FrequencyResponse Restrict(const ident::FrequencyResponse& frf, const std::vector<char>& used) {
  ident::FrequencyResponse r = frf;
  r.f_hz.clear(); r.H.clear(); r.coherence.clear(); r.H_std.clear(); r.S_uu.clear(); r.S_yy.clear(); r.S_uy.clear();
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    if (!used[k]) continue;
    r.f_hz.push_back(frf.f_hz[k]);
    r.H.push_back(frf.H[k]);
    r.coherence.push_back(k < frf.coherence.size() ? frf.coherence[k] : 1.0);
    r.H_std.push_back(frf.H_std[k]);
    if (k < frf.S_uu.size()) r.S_uu.push_back(frf.S_uu[k]);
    if (k < frf.S_yy.size()) r.S_yy.push_back(frf.S_yy[k]);
    if (k < frf.S_uy.size()) r.S_uy.push_back(frf.S_uy[k]);
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

// What one order's fit needs beyond FitResult: the per-bin weighted
// residuals of the final fit, for the quality tests.
struct Fixed {
  FitResult res;
  std::vector<double> f_hz;
  std::vector<cd> r;  // (H - G) / s per used bin
};

// Fits n sections to the used bins `sub` for each delay of `delays` (or of the
// automatic search), from the automatic starts and `extra` starts.
Fixed FitFixed(const ident::FrequencyResponse& sub, const FitOptions& o, int n, const std::vector<Plant>& extra) {
  const int p = 2 + 4 * n;
  Fixed out;
  FitResult& res = out.res;
  res.num_parameters = p;
  const size_t usable = MakeBins(sub, 0, o.relative_std_floor).z.size();
  if (static_cast<int>(2 * usable) <= p) {
    throw InputError("the response has " + std::to_string(usable) + " usable bins, too few for " +
                     std::to_string(p) + " parameters; widen --fmin/--fmax or use fewer --modes");
  }
  int best_delay = -1;
  SingleFit best;
  // Every screened start at the best delay, for the runners-up below.
  std::vector<std::pair<SingleFit, int>> screened;
  std::vector<double> tried_cost;  // by delay
  auto try_delay = [&](int d) {
    if (d < 0 || (d < static_cast<int>(tried_cost.size()) && std::isfinite(tried_cost[d]))) return;
    std::vector<Plant> starts;
    if (o.init && static_cast<int>(o.init->modes.size()) == n) starts.push_back(*o.init);
    for (const Plant& s : extra) starts.push_back(s);
    for (Plant& s : AutomaticStarts(sub, n, d, o.max_starts)) starts.push_back(s);
    // Screen every start with a few iterations on every 6th bin; only the
    // best goes on to convergence on all bins below (most of the time would
    // otherwise go into starts that lose).
    FitOptions screen = o;
    screen.max_iterations = std::min(o.max_iterations, 8);
    const Bins coarse = MakeBins(sub, d, o.relative_std_floor, usable > 600 ? 6 : 1);
    double best_here = std::numeric_limits<double>::infinity();
    for (const Plant& s : starts) {
      ++res.starts_tried;
      std::vector<double> xs = ToLog(s);
      const SingleFit f = Solve(coarse, n, xs, screen);
      res.iterations += f.iterations;
      best_here = std::min(best_here, f.cost);
      if (std::isfinite(f.cost)) screened.push_back({f, d});
      if (f.cost < best.cost) {
        best = f;
        best_delay = d;
      }
    }
    if (static_cast<int>(tried_cost.size()) <= d) tried_cost.resize(d + 1, std::numeric_limits<double>::quiet_NaN());
    tried_cost[d] = std::isfinite(best_here) ? best_here : 1e300;
  };
  if (!o.auto_delay) {
    try_delay(o.delay_samples);
  } else {
    const double suggested = PhaseSlopeDelay(sub);
    const int d0 = std::isfinite(suggested) ? std::clamp(static_cast<int>(std::lround(suggested)), 0, o.max_auto_delay) : 0;
    const int lo = std::max(0, d0 - 2), hi = std::min(o.max_auto_delay, d0 + 2);
    for (int d = lo; d <= hi; ++d) try_delay(d);
    // Extend while the best is at an end of the range that is not a limit.
    for (int d = hi + 1; d <= o.max_auto_delay && best_delay == d - 1; ++d) try_delay(d);
    for (int d = lo - 1; d >= 0 && best_delay == d + 1; --d) try_delay(d);
    int tlo = 0;
    while (tlo < static_cast<int>(tried_cost.size()) && !std::isfinite(tried_cost[tlo])) ++tlo;
    std::ostringstream why;
    why << "delay " << best_delay << " samples: the lowest screened cost among " << tlo << ".."
        << tried_cost.size() - 1 << " (phase slope of the upper band suggested ";
    if (std::isfinite(suggested)) why << std::setprecision(3) << suggested; else why << "nothing";
    why << "; searched up to " << o.max_auto_delay << ")";
    res.delay_choice = why.str();
  }
  if (best_delay < 0 || !std::isfinite(best.cost)) {
    res.status = FitStatus::kNoConvergence;
    res.message = "no start produced a usable fit";
    return out;
  }
  // Converge from the best screened point and from the runners-up whose
  // screened cost is within o.runner_up_cost_ratio of it (at most
  // o.max_converged_starts in all): eight iterations on a sixth of the bins do
  // not always rank nearby basins right (closely spaced modes).
  std::sort(screened.begin(), screened.end(), [](const auto& a, const auto& b) { return a.first.cost < b.first.cost; });
  Bins bins;
  SingleFit fin;
  int converged_starts = 0;
  for (size_t i = 0; i < screened.size() && converged_starts < o.max_converged_starts; ++i) {
    if (i > 0 && screened[i].first.cost > o.runner_up_cost_ratio * screened[0].first.cost) break;
    ++converged_starts;
    Bins here = MakeBins(sub, screened[i].second, o.relative_std_floor);
    std::vector<double> xs = screened[i].first.x;
    const SingleFit f = Solve(here, n, xs, o);
    res.iterations += f.iterations;
    if (i == 0 || (f.converged && !fin.converged) || (f.converged == fin.converged && f.cost < fin.cost)) {
      fin = f;
      bins = std::move(here);
      best_delay = screened[i].second;
    }
  }
  const std::vector<double>& x = fin.x;
  res.status = fin.converged ? FitStatus::kConverged : FitStatus::kNoConvergence;
  res.message = fin.message;
  res.cost = fin.cost;
  res.num_residuals = 2 * static_cast<int>(bins.z.size());
  res.plant = FromLog(x, n);
  res.plant.delay_samples = best_delay;
  const int dof = res.num_residuals - p;
  res.chi2_per_dof = 2.0 * res.cost / dof;
  res.std_scale = res.chi2_per_dof * std::max(1.0, sub.bin_correlation);

  // Standard errors: covariance in log space (LogCovariance), scaled, then the delta
  // method to (m, b, w, c, v, d).
  res.std_errors = res.plant;
  const double inf = std::numeric_limits<double>::infinity();
  res.std_errors.m = res.std_errors.b = inf;
  for (Mode& md : res.std_errors.modes) md = {inf, inf, inf, inf};
  std::vector<double> fit_cov;  // scaled, in the solver's log space
  if (std::vector<double> S; LogCovariance(bins, n, x, &S)) {
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
      const cd wr = (bins.H[k] - model) * bins.weight[k];
      out.r.push_back(wr);
      out.f_hz.push_back(std::arg(bins.z[k]) / (kHz * bins.period_s));
      if (std::abs(wr) > worst) { worst = std::abs(wr); worst_k = k; }
    }
    res.nrmse_fit_percent = 100.0 * (1.0 - std::sqrt(err2 / var2));
    res.worst_misfit_hz = out.f_hz[worst_k];
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
  return out;
}

// Starts for n + 1 sections from an n-section fit: its sections kept, a new
// one placed where the weighted misfit peaks (the unmodelled mode's
// resonance/antiresonance pair sits there), as a pole above a zero and as a
// zero above a pole, at the three largest misfit peaks; and each section
// split in two.
std::vector<Plant> GrowStarts(const Fixed& prev) {
  std::vector<Plant> out;
  const size_t nb = prev.r.size();
  if (nb < 8) return out;
  const int h = std::max<int>(2, static_cast<int>(nb / 100));
  std::vector<double> sm(nb);
  for (size_t k = 0; k < nb; ++k) {
    double a = 0; int c = 0;
    for (long j = static_cast<long>(k) - h; j <= static_cast<long>(k) + h; ++j) {
      if (j < 0 || j >= static_cast<long>(nb)) continue;
      a += std::norm(prev.r[j]); ++c;
    }
    sm[k] = a / c;
  }
  const std::vector<Extremum> peaks = Peaks(sm);
  for (size_t i = 0; i < peaks.size() && i < 3; ++i) {
    const double w = kHz * prev.f_hz[peaks[i].index];
    for (const auto& [fp, fz] : {std::pair{1.08, 0.92}, std::pair{1.0, 0.8}, std::pair{1.25, 1.0}}) {
      Plant p = prev.res.plant;
      p.modes.push_back({w * fp, 2 * 0.05 * w * fp, w * fz, 2 * 0.05 * w * fz});
      CanonicalOrder(&p, nullptr);
      out.push_back(p);
    }
  }
  // Each section split in two, 8 % apart (two close modes that the smaller
  // fit merged into one).
  for (size_t i = 0; i < prev.res.plant.modes.size(); ++i) {
    Plant p = prev.res.plant;
    const Mode m = p.modes[i];
    p.modes[i] = {m.omega * 0.92, m.c * 0.5, m.v * 0.92, m.d * 0.5};
    p.modes.push_back({m.omega * 1.08, m.c * 0.5, m.v * 1.08, m.d * 0.5});
    CanonicalOrder(&p, nullptr);
    out.push_back(p);
  }
  return out;
}

// BIC on the weighted residual: chi2 / (kappa s2) + p ln(N / kappa), with
// kappa the bins' correlation (N / kappa independent residuals) and s2 the
// noise level that the per-bin std misses, read from the largest model (as
// Mallows' Cp does): the lowest chi2/dof of all orders tried, at least 1.
double Bic(const FitResult& r, double kappa, double s2) {
  kappa = std::max(1.0, kappa);
  return 2.0 * r.cost / (kappa * std::max(1.0, s2)) + r.num_parameters * std::log(r.num_residuals / kappa);
}

std::string Fmt(const char* fmt, double a, double b = 0, double c = 0, double d = 0) {
  char s[300];
  std::snprintf(s, sizeof s, fmt, a, b, c, d);
  return s;
}

// chi2/dof above which the model does not explain the response: 1.5 (on
// correct models with >= 8 averages chi2/dof is 1.0-1.4, the per-bin std
// being estimated from the same averages) plus 4 standard deviations of
// chi2/dof for correlated bins, 4 sqrt(2 kappa / dof).
double Chi2Limit(const FitResult& r, double kappa) {
  const int dof = std::max(1, r.num_residuals - r.num_parameters);
  return 1.5 + 4.0 * std::sqrt(2.0 * std::max(1.0, kappa) / dof);
}

// The quality tests (see FitResult::quality).
void JudgeQuality(const Fixed& fx, const ident::FrequencyResponse& sub, const FitOptions& o, FitResult* res) {
  auto add = [&](std::string code, std::string msg, std::string advice) {
    res->reasons.push_back({std::move(code), std::move(msg), std::move(advice)});
  };
  const double kappa = std::max(1.0, sub.bin_correlation);
  const double chi_limit = Chi2Limit(*res, sub.bin_correlation);
  if (res->chi2_per_dof > chi_limit) {
    add("chi2_per_dof", Fmt("chi2/dof %.3g is above %.3g: the model does not explain the response within its std",
                            res->chi2_per_dof, chi_limit),
        "try more modes (--modes auto), --delay-samples auto, or a band where the device is linear (--fmin/--fmax)");
  }
  // Runs test on every 3rd bin (Hann bins 3 apart are uncorrelated).
  const int stride = kappa > 1.2 ? 3 : 1;
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
        "the model misses a feature of the response: more modes (--modes auto), a delay (--delay-samples auto)");
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
          "a mode there is missing or wrong: more modes, or leave that band out (--fmin/--fmax)");
    }
  }
  if (sub.num_averages < o.min_averages) {
    add("few_averages", "the response averages " + std::to_string(sub.num_averages) +
                            " Welch segment(s): its per-bin std, hence the weights and the standard errors, mean little",
        "record a longer log or use a shorter --window-length");
  }
  for (const std::string& s : SpuriousSections(*res, o)) {
    const bool bound = s.find("bound") != std::string::npos;
    add(bound ? "parameter_at_bound" : "spurious_section", s,
        bound ? "the data may not support this many modes: fewer modes (--modes auto)"
              : "fewer modes (--modes auto) or a wider band");
  }
}

}  // namespace

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
  const Plant& p = r.plant;
  const double nyq_w = std::numbers::pi * r.band_sample_rate_hz;
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const std::string name = "section " + std::to_string(i + 1);
    const Mode& md = p.modes[i];
    // Nearest zero to this pole.
    size_t j = 0;
    for (size_t q = 1; q < p.modes.size(); ++q) {
      if (std::abs(std::log(p.modes[q].v / md.omega)) < std::abs(std::log(p.modes[j].v / md.omega))) j = q;
    }
    const Mode& mz = p.modes[j];
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
      const Mode& e = r.std_errors.modes[i];
      if (!(e.omega < md.omega && e.c < md.c && e.v < md.v && e.d < md.d)) {
        out.push_back(name + ": a parameter's std is larger than its value (or unknown)");
      }
    }
    if (r.band.num_used > 0) {
      const double lo = kHz * r.band.f_lo_hz / 1.05, hi = kHz * r.band.f_hi_hz * 1.05;
      if (md.omega < lo || md.omega > hi || md.v < lo || md.v > hi) {
        out.push_back(name + Fmt(": pole %.4g Hz or zero %.4g Hz is outside the used band", md.omega / kHz, md.v / kHz));
      }
    }
  }
  return out;
}

FitResult FitModel(const ident::FrequencyResponse& frf, const FitOptions& o) {
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
                     " samples at this window), use a shorter window (e.g. --window-length " + std::to_string(w) +
                     ", at the cost of frequency resolution), or --allow-short to fit anyway (judged poor)");
  }
  const ident::ExcitedBand band = ident::SelectExcitedBand(frf, o.band);
  const ident::FrequencyResponse sub = Restrict(frf, band.used);
  FitResult res;
  Fixed chosen;
  if (!o.auto_modes) {
    chosen = FitFixed(sub, o, o.num_modes, {});
    // A fit with a spurious section may sit in a wrong minimum where two
    // closely spaced modes merge and the spare section parks anywhere: fit
    // one section fewer, grow it back where its misfit peaks, and keep the
    // better of the two. Only then, so the usual fit costs nothing more.
    chosen.res.band = band;
    chosen.res.band_sample_rate_hz = frf.sample_rate_hz;
    const bool suspect = chosen.res.status != FitStatus::kConverged || !SpuriousSections(chosen.res, o).empty() ||
                         chosen.res.chi2_per_dof > Chi2Limit(chosen.res, sub.bin_correlation);
    if (o.num_modes >= 1 && o.retry_spurious && suspect) {
      FitOptions lower = o;
      lower.auto_delay = false;
      lower.delay_samples = chosen.res.plant.delay_samples;
      lower.init.reset();
      lower.max_converged_starts = std::max(o.max_converged_starts, 8);
      lower.runner_up_cost_ratio = std::max(o.runner_up_cost_ratio, 10.0);
      const Fixed prev = FitFixed(sub, lower, o.num_modes - 1, {});
      if (prev.res.status == FitStatus::kConverged) {
        Fixed again = FitFixed(sub, lower, o.num_modes, GrowStarts(prev));
        again.res.starts_tried += chosen.res.starts_tried + prev.res.starts_tried;
        again.res.iterations += chosen.res.iterations + prev.res.iterations;
        again.res.delay_choice = chosen.res.delay_choice;
        if (again.res.status == FitStatus::kConverged &&
            (chosen.res.status != FitStatus::kConverged || again.res.cost < chosen.res.cost)) {
          chosen = std::move(again);
        }
      }
    }
    res = chosen.res;
  } else {
    std::vector<Fixed> fits;
    std::vector<OrderTrial> table;
    const double kappa = std::max(1.0, sub.bin_correlation);
    int pick = -1;
    for (int n = 0; n <= o.max_modes; ++n) {
      if (2 * band.num_used <= 2 + 4 * n) break;
      std::vector<Plant> extra;
      if (n > 0 && fits.back().res.status == FitStatus::kConverged) extra = GrowStarts(fits.back());
      fits.push_back(FitFixed(sub, o, n, extra));
      Fixed& fx = fits.back();
      fx.res.band = band;
      fx.res.band_sample_rate_hz = frf.sample_rate_hz;
      OrderTrial t;
      t.num_modes = n;
      t.converged = fx.res.status == FitStatus::kConverged;
      t.chi2_per_dof = fx.res.chi2_per_dof;
      t.delay_samples = fx.res.plant.delay_samples;
      for (const Mode& md : fx.res.plant.modes) t.pole_hz.push_back(md.omega / kHz);
      for (double f : t.pole_hz) {
        bool persists = false;
        if (n > 0) for (double g : table.back().pole_hz) persists |= std::abs(f / g - 1) < 0.02;
        t.persists.push_back(persists);
      }
      t.spurious = SpuriousSections(fx.res, o);
      if (!t.converged) t.spurious.push_back("the solver did not converge");
      table.push_back(t);
    }
    double s2 = std::numeric_limits<double>::infinity();
    for (const Fixed& fx : fits) if (fx.res.status == FitStatus::kConverged) s2 = std::min(s2, fx.res.chi2_per_dof);
    if (!std::isfinite(s2)) s2 = 1.0;
    for (size_t i = 0; i < table.size(); ++i) {
      table[i].bic = Bic(fits[i].res, kappa, s2);
      if (table[i].spurious.empty() && (pick < 0 || table[i].bic < table[pick].bic)) pick = static_cast<int>(i);
    }
    if (pick < 0) pick = 0;
    chosen = fits[pick];
    res = chosen.res;
    res.order_table = table;
    std::ostringstream os;
    os << pick << " modes: the lowest BIC (" << std::setprecision(6) << table[pick].bic
       << ") among the orders 0.." << table.size() - 1 << " without a spurious section";
    for (const OrderTrial& t : table) {
      if (t.num_modes > pick && !t.spurious.empty()) {
        os << "; " << t.num_modes << " rejected (" << t.spurious.front() << ")";
        break;
      }
    }
    res.order_choice = os.str();
  }
  res.band = band;
  res.band_sample_rate_hz = frf.sample_rate_hz;
  if (frf.num_averages == 1) {
    res.warnings.push_back("the log gives a single Welch segment: coherence is then 1 and says nothing, "
                           "and the standard errors are not meaningful; use a longer log or a shorter window");
  }
  {
    std::vector<double> c = sub.coherence;
    std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
    if (c[c.size() / 2] < 0.5) {
      res.warnings.push_back("coherence is below 0.5 over most of the band: the response is dominated by "
                             "noise or nonlinearity; the fit may be poor");
    }
  }
  if (res.status == FitStatus::kConverged) {
    JudgeQuality(chosen, sub, o, &res);
    if (o.auto_modes && res.plant.modes.size() == static_cast<size_t>(o.max_modes) && o.max_modes > 0) {
      res.reasons.push_back({"order_search_at_limit",
                             "the order search chose its maximum, " + std::to_string(o.max_modes) + " modes",
                             "raise --max-modes, or narrow the band to the modes that matter"});
    }
    if (o.auto_delay && res.plant.delay_samples >= o.max_auto_delay) {
      res.reasons.push_back({"delay_search_at_limit",
                             "the delay search chose its maximum, " + std::to_string(o.max_auto_delay) + " samples",
                             "check the log's timing (a constant input-output offset), or give --delay-samples"});
    }
    res.quality = res.reasons.empty() ? FitQuality::kGood : FitQuality::kPoor;
  }
  return res;
}

std::string FitResult::BriefReport() const {
  std::ostringstream os;
  os << "fit " << ToString(status) << ": chi2/dof " << chi2_per_dof << ", fit " << nrmse_fit_percent
     << "% (NRMSE of H; unweighted, so a large misfit where |H| is small hardly shows), worst misfit at "
     << worst_misfit_hz << " Hz, " << starts_tried << " starts, " << iterations << " iterations";
  return os.str();
}

}  // namespace zwidth::fit
