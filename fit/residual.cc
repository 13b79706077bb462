// The weighted ZOH residual of eq. (1) as a Ceres cost function, one bounded
// Ceres solve, and the parameter covariance at its solution.
#include <algorithm>
#include <cmath>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/jet.h>
#include <Eigen/Dense>

#include "fit/fit_internal.h"
#include "model/zoh_modal.h"

namespace zwidth::fit::internal {

// Every `stride`-th bin (stride > 1 for the cheap screening of starts).
Bins MakeBins(const ident::FrequencyResponse& frf, int delay, double floor, int stride) {
  Bins b;
  b.period_s = frf.period_s();
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
  // d(coefficient)/dx of the pole-residue form, by ceres::Jet, 8 at a time.
  struct CoefficientGradients {
    std::vector<double> dI, dea, dca;  // integrator, rigid pole, rigid coefficient [param]
    std::vector<cd> dE, dC;            // section pole, coefficient [mode * p_ + param]
    // dE of mode i is non-zero only in [de_lo[i], de_hi[i]) (its pole's own
    // omega and damping ratio): the pole's terms are added only there.
    std::vector<int> de_lo, de_hi;
  };
  bool Gradients(const double* x, CoefficientGradients* d) const {
    d->dI.assign(p_, 0.0); d->dea.assign(p_, 0.0); d->dca.assign(p_, 0.0);
    d->dE.assign(n_ * p_, 0.0); d->dC.assign(n_ * p_, 0.0);
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
      model::ZohModalForm<J> fj;
      if (!fj.Build(m, b, sec.data(), n_, bins_->period_s)) return false;
      for (int q = s; q < std::min(p_, s + 8); ++q) {
        d->dI[q] = fj.integrator.v[q - s];
        d->dea[q] = fj.rigid_pole.v[q - s];
        d->dca[q] = fj.rigid_coeff.v[q - s];
        for (int i = 0; i < n_; ++i) {
          d->dE[i * p_ + q] = cd(fj.pole[i].re.v[q - s], fj.pole[i].im.v[q - s]);
          d->dC[i * p_ + q] = cd(fj.coeff[i].re.v[q - s], fj.coeff[i].im.v[q - s]);
        }
      }
    }
    d->de_lo.assign(n_, p_);
    d->de_hi.assign(n_, 0);
    for (int i = 0; i < n_; ++i) {
      for (int q = 0; q < p_; ++q) {
        if (d->dE[i * p_ + q] == cd(0.0)) continue;
        d->de_lo[i] = std::min(d->de_lo[i], q);
        d->de_hi[i] = q + 1;
      }
    }
    return true;
  }

  bool EvaluateUncached(const double* x, double* residuals, double* jacobian) const {
    const int nb = static_cast<int>(bins_->z.size());
    model::ZohModalForm<double> f;
    {
      double m, b;
      std::vector<double> sec;
      Physical(x, n_, &m, &b, &sec);
      if (!f.Build(m, b, sec.data(), n_, bins_->period_s)) return false;
    }
    const bool want_j = jacobian != nullptr;
    // Gradients of each coefficient with respect to x.
    CoefficientGradients d;
    if (want_j && !Gradients(x, &d)) return false;
    const std::vector<double>&dI = d.dI, &dea = d.dea, &dca = d.dca;
    const std::vector<cd>&dE = d.dE, &dC = d.dC;
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
          // The pole's terms b1 de + b2 conj(de) where de can be non-zero;
          // elsewhere they are exact zeros, left out (the same sums, bit for bit).
          const int lo = d.de_lo[i], hi = std::max(lo, d.de_hi[i]);
          for (int q = 0; q < lo; ++q) grad[q] += dc[q] * q1 + std::conj(dc[q]) * q2;
          for (int q = lo; q < hi; ++q) {
            grad[q] += dc[q] * q1 + b1 * de[q] + std::conj(dc[q]) * q2 + b2 * std::conj(de[q]);
          }
          for (int q = hi; q < p_; ++q) grad[q] += dc[q] * q1 + std::conj(dc[q]) * q2;
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

std::vector<double> ToLog(const model::Plant& p) {
  std::vector<double> x = {std::log(p.m), std::log(p.b)};
  for (const model::Mode& md : p.modes) {
    x.push_back(std::log(md.omega));
    x.push_back(std::log(md.c / (2.0 * md.omega)));
    x.push_back(std::log(md.v));
    x.push_back(std::log(md.d / (2.0 * md.v)));
  }
  return x;
}

model::Plant FromLog(const std::vector<double>& x, int n) {
  model::Plant p;
  std::vector<double> sec;
  Physical(x.data(), n, &p.m, &p.b, &sec);
  for (int i = 0; i < n; ++i) p.modes.push_back({sec[4 * i], sec[4 * i + 1], sec[4 * i + 2], sec[4 * i + 3]});
  return p;
}

// (J^T J)^-1 of the weighted residual at x, row-major p x p, as Ceres'
// DENSE_SVD covariance computes it (null_space_rank 0: refused when
// (sigma_min / sigma_max)^2 < 1e-14), but from the SVD of R of J = QR (p x p)
// instead of the SVD of the tall J with its thin U: J and R have the same
// singular values and right vectors. false when J is near rank deficient or
// cannot be evaluated.
bool LogCovariance(const Bins& bins, int n, const std::vector<double>& x, std::vector<double>* cov,
                   Eigen::MatrixXd* jacobian, Eigen::VectorXd* residuals_out) {
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
  if (jacobian) *jacobian = J;
  if (residuals_out) *residuals_out = Eigen::Map<const Eigen::VectorXd>(residuals.data(), rows);
  return true;
}

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

}  // namespace zwidth::fit::internal
