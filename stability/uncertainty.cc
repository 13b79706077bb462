#include "stability/uncertainty.h"

#include "model/cancel.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Dense>

#include "model/c_locale.h"
#include "model/error.h"
#include "model/state_space.h"

namespace zwidth::stability {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::MatrixXd CovMatrix(const model::Plant& plant, const std::vector<double>& cov) {
  CheckLogCovariance(plant, cov);
  const int p = NumLogParameters(plant);
  return Eigen::Map<const Eigen::MatrixXd>(cov.data(), p, p);  // symmetric: order irrelevant
}

double Quad(const Eigen::VectorXd& g, const Eigen::MatrixXd& S) {
  if (!g.allFinite()) return kNaN;
  return std::sqrt(std::max(0.0, g.dot(S * g)));
}

}  // namespace

int NumLogParameters(const model::Plant& plant) { return 2 + 4 * static_cast<int>(plant.modes.size()); }

std::vector<std::string> LogParameterNames(const model::Plant& plant) {
  std::vector<std::string> n = {"m", "b"};
  for (size_t i = 0; i < plant.modes.size(); ++i) {
    for (const char* k : {"omega", "c", "v", "d"}) n.push_back("modes[" + std::to_string(i) + "]." + k);
  }
  return n;
}

model::Plant PerturbLog(const model::Plant& plant, const std::vector<double>& dx) {
  model::Plant p = plant;
  p.m *= std::exp(dx[0]);
  p.b *= std::exp(dx[1]);
  for (size_t i = 0; i < p.modes.size(); ++i) {
    p.modes[i].omega *= std::exp(dx[2 + 4 * i]);
    p.modes[i].c *= std::exp(dx[3 + 4 * i]);
    p.modes[i].v *= std::exp(dx[4 + 4 * i]);
    p.modes[i].d *= std::exp(dx[5 + 4 * i]);
  }
  return p;
}

bool UncertaintyOptions::IsValid(std::string* why) const {
  if (!(log_step > 0.0 && log_step < 0.1)) {
    if (why) *why = "UncertaintyOptions::log_step must be in (0, 0.1)";
    return false;
  }
  return true;
}

void CheckLogCovariance(const model::Plant& plant, const std::vector<double>& cov) {
  const size_t p = static_cast<size_t>(NumLogParameters(plant));
  if (cov.size() != p * p) {
    throw InputError("the parameter covariance has " + std::to_string(cov.size()) + " entries; a model with " +
                     std::to_string(plant.modes.size()) + " sections needs " + std::to_string(p * p) +
                     " ((2 + 4 N)^2)");
  }
  double scale = 0.0;
  for (double v : cov) {
    if (!std::isfinite(v)) throw InputError("the parameter covariance has a non-finite entry");
    scale = std::max(scale, std::abs(v));
  }
  for (size_t i = 0; i < p; ++i) {
    if (cov[i * p + i] > kMaxLogVariance) {
      const std::string sd = FormatG(std::sqrt(cov[i * p + i]));
      throw InputError("the parameter covariance gives log(" + LogParameterNames(plant)[i] + ") a variance of " +
                       FormatG(cov[i * p + i]) + " (a std of " + sd + " in its natural log, a factor of e^" + sd +
                       "); the covariance is of the parameters' natural logs (relative: 1e-4 is a 1 % std) and at "
                       "most " + FormatG(kMaxLogVariance) +
                       ": convert an absolute covariance C to C_ij / (x_i x_j), or drop the covariance");
    }
    for (size_t j = 0; j < i; ++j) {
      if (std::abs(cov[i * p + j] - cov[j * p + i]) > 1e-9 * scale) {
        throw InputError("the parameter covariance is not symmetric (entry " + std::to_string(i) + "," +
                         std::to_string(j) + ")");
      }
    }
  }
  const Eigen::MatrixXd S = Eigen::Map<const Eigen::MatrixXd>(cov.data(), p, p);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (S + S.transpose()));
  if (p > 0 && es.eigenvalues().minCoeff() < -1e-9 * scale) {
    throw InputError("the parameter covariance is not positive semi-definite (smallest eigenvalue " +
                     FormatG(es.eigenvalues().minCoeff()) + ")");
  }
}

PerturbedPlants SamplePerturbedPlants(const model::Plant& plant, double T, const Hand& hand, const UncertaintyOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("uncertainty options: " + why);
  PerturbedPlants r{SampledPlant(plant, T, hand), {}, {}, o.log_step};
  const int p = NumLogParameters(plant);
  for (int i = 0; i < p; ++i) {
    std::vector<double> dx(p, 0.0);
    dx[i] = o.log_step;
    r.plus.emplace_back(PerturbLog(plant, dx), T, hand);
    dx[i] = -o.log_step;
    r.minus.emplace_back(PerturbLog(plant, dx), T, hand);
  }
  return r;
}

std::vector<double> KcrStd(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                           const std::vector<CriticalPoint>& points, const UncertaintyOptions& o,
                           const LoopOptions& loop) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("uncertainty options: " + why);
  CheckLogCovariance(plant, cov);
  return KcrStd(SamplePerturbedPlants(plant, T, loop.hand, o), cov, delay, points, loop);
}

std::vector<double> KcrStd(const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                           const std::vector<CriticalPoint>& points, const LoopOptions& loop) {
  const model::Plant& plant = pl.nominal.plant();
  const double T = pl.nominal.period_s();
  const Eigen::MatrixXd S = CovMatrix(plant, cov);
  const int p = NumLogParameters(plant);
  const int D = delay + plant.delay_samples;
  // V(theta) = F(e^{j theta}) (1 - e^{-j theta}) / T.
  auto V = [&](double th) {
    const std::complex<double> zi = std::polar(1.0, -th);
    std::complex<double> F = 1.0;
    if (loop.HasFilter()) {
      std::complex<double> nb = 0.0, na = 0.0;
      for (size_t i = loop.filter_b.size(); i-- > 0;) nb = nb * zi + loop.filter_b[i];
      for (size_t i = loop.filter_a.size(); i-- > 0;) na = na * zi + loop.filter_a[i];
      F = nb / na;
    }
    return F * (1.0 - zi) / T;
  };
  // G_d by the state-space (Hessenberg) solve, as the delta method was validated with.
  auto W = [&](const SampledPlant& g, double th) {
    return -std::polar(1.0, th * D) / g.GdStateSpace(std::polar(1.0, th));
  };
  const SampledPlant& g0 = pl.nominal;
  const std::vector<SampledPlant>& gp = pl.plus;
  const std::vector<SampledPlant>& gm = pl.minus;
  const UncertaintyOptions o{pl.log_step};
  std::vector<double> out(points.size(), kNaN);
  for (size_t k = 0; k < points.size(); ++k) {
    const CriticalPoint& c = points[k];
    if (c.K_cr == 0.0) { out[k] = 0.0; continue; }
    if (!std::isfinite(c.K_cr) || !std::isfinite(c.f_cr_hz)) continue;
    const double th = 2.0 * std::numbers::pi * c.f_cr_hz * T;
    Eigen::VectorXd grad(p);
    const bool at_pi = std::abs(th - std::numbers::pi) < 1e-12;
    const double h = 1e-6;
    const std::complex<double> Wth =
        at_pi ? 0.0 : (W(g0, th + h) - W(g0, th - h)) / (2.0 * h);
    // V_theta: exact for the raw difference (sin, cos), else central differences.
    const std::complex<double> Vth = !loop.HasFilter()
                                         ? std::complex<double>(std::sin(th), std::cos(th)) / T
                                         : (at_pi ? 0.0 : (V(th + h) - V(th - h)) / (2.0 * h));
    const double den = c.B * Vth.imag() - Wth.imag();
    for (int i = 0; i < p; ++i) {
      const std::complex<double> Wx = (W(gp[i], th) - W(gm[i], th)) / (2.0 * o.log_step);
      if (at_pi) { grad[i] = Wx.real(); continue; }
      const double dth = Wx.imag() / den;
      grad[i] = Wx.real() + (Wth.real() - c.B * Vth.real()) * dth;
    }
    out[k] = Quad(grad, S);
  }
  return out;
}

SummaryStd SummaryStdDelta(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                           const DelaySummary& nominal, const UncertaintyOptions& o, const LoopOptions& loop) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("uncertainty options: " + why);
  CheckLogCovariance(plant, cov);
  return SummaryStdDelta(SamplePerturbedPlants(plant, T, loop.hand, o), cov, delay, nominal, loop);
}

SummaryStd SummaryStdDelta(const PerturbedPlants& pl, const std::vector<double>& cov, int delay,
                           const DelaySummary& nominal, const LoopOptions& loop) {
  const model::Plant& plant = pl.nominal.plant();
  const Eigen::MatrixXd S = CovMatrix(plant, cov);
  const int p = NumLogParameters(plant);
  const UncertaintyOptions o{pl.log_step};
  Eigen::MatrixXd J(4, p);
  for (int i = 0; i < p; ++i) {
    SummaryStd q[2];
    for (int s = 0; s < 2; ++s) q[s] = ZWidth(s == 0 ? pl.plus[i] : pl.minus[i], delay, loop).SummarizeNear(nominal);
    J(0, i) = (q[0].K_cr_at_zero_B - q[1].K_cr_at_zero_B) / (2 * o.log_step);
    J(1, i) = (q[0].B_t - q[1].B_t) / (2 * o.log_step);
    J(2, i) = (q[0].K_cr_max - q[1].K_cr_max) / (2 * o.log_step);
    J(3, i) = (q[0].B_max - q[1].B_max) / (2 * o.log_step);
  }
  SummaryStd r;
  if (std::isfinite(nominal.K_cr_at_zero_B)) r.K_cr_at_zero_B = nominal.K_cr_at_zero_B == 0.0 ? 0.0 : Quad(J.row(0).transpose(), S);
  if (nominal.has_transition) r.B_t = Quad(J.row(1).transpose(), S);
  if (std::isfinite(nominal.K_cr_max)) r.K_cr_max = Quad(J.row(2).transpose(), S);
  if (std::isfinite(nominal.B_max) && nominal.B_max > 0.0) r.B_max = Quad(J.row(3).transpose(), S);
  return r;
}

MonteCarloResult SummaryMonteCarlo(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                                   int samples, std::uint64_t seed, const LoopOptions& loop) {
  if (samples < 2) throw InputError("SummaryMonteCarlo::samples must be >= 2");
  const Eigen::MatrixXd S = CovMatrix(plant, cov);
  const int p = NumLogParameters(plant);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  const Eigen::MatrixXd L = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  double sum[4] = {0, 0, 0, 0}, sum2[4] = {0, 0, 0, 0};
  int cnt[4] = {0, 0, 0, 0};
  for (int k = 0; k < samples; ++k) {
    PollCancel();  // model/cancel.h: a host's Ctrl-C
    Eigen::VectorXd u(p);
    for (int i = 0; i < p; ++i) u[i] = n01(rng);
    const Eigen::VectorXd dx = L * u;
    const DelaySummary s =
        ZWidth(PerturbLog(plant, std::vector<double>(dx.data(), dx.data() + p)), T, delay, loop).Summarize();
    const double v[4] = {s.K_cr_at_zero_B, s.has_transition ? s.B_t : kNaN, s.K_cr_max, s.B_max};
    for (int q = 0; q < 4; ++q) {
      if (!std::isfinite(v[q])) continue;
      sum[q] += v[q];
      sum2[q] += v[q] * v[q];
      ++cnt[q];
    }
  }
  MonteCarloResult r;
  r.samples = samples;
  double* sd[4] = {&r.std.K_cr_at_zero_B, &r.std.B_t, &r.std.K_cr_max, &r.std.B_max};
  double* mn[4] = {&r.mean.K_cr_at_zero_B, &r.mean.B_t, &r.mean.K_cr_max, &r.mean.B_max};
  for (int q = 0; q < 4; ++q) {
    if (cnt[q] < 2) continue;
    const double m = sum[q] / cnt[q];
    *mn[q] = m;
    *sd[q] = std::sqrt(std::max(0.0, (sum2[q] - cnt[q] * m * m) / (cnt[q] - 1)));
  }
  r.used_K_cr_at_zero_B = cnt[0];
  r.used_B_t = cnt[1];
  r.used_K_cr_max = cnt[2];
  r.used_B_max = cnt[3];
  return r;
}

}  // namespace zwidth::stability
