// The friction fit (fit/friction_fit.h): IDIM-LS on the band-limited
// derivatives of the encoder, iterated with the frequency-domain refit.
#include "fit/friction_fit.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <cstdio>
#include <numbers>

#include <Eigen/Dense>

#include "model/error.h"

namespace zwidth::fit {
namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Num(const char* fmt, double a, double b = 0.0) {
  char s[200];
  std::snprintf(s, sizeof s, fmt, a, b);
  return s;
}

// The rigid body's band-limited velocity and acceleration at the sample
// instants, from the encoder (step 1).
struct Motion {
  std::vector<double> v, a;
};

std::vector<cd> Forward(std::vector<double> x) {
  std::vector<cd> X(x.size() / 2 + 1);
  fftw_plan p = fftw_plan_dft_r2c_1d(static_cast<int>(x.size()), x.data(), reinterpret_cast<fftw_complex*>(X.data()),
                                     FFTW_ESTIMATE);
  fftw_execute(p);
  fftw_destroy_plan(p);
  return X;
}

std::vector<double> Inverse(std::vector<cd> X, size_t n) {
  std::vector<double> x(n);
  fftw_plan p = fftw_plan_dft_c2r_1d(static_cast<int>(n), reinterpret_cast<fftw_complex*>(X.data()), x.data(),
                                     FFTW_ESTIMATE);
  fftw_execute(p);
  fftw_destroy_plan(p);
  for (double& s : x) s /= static_cast<double>(n);
  return x;
}

// L(f): 1 up to fc, cos^2 down to 0 at 1.5 fc.
double LowPass(double f, double fc) {
  if (f <= fc) return 1.0;
  if (f >= 1.5 * fc) return 0.0;
  const double c = std::cos(0.5 * std::numbers::pi * (f - fc) / (0.5 * fc));
  return c * c;
}

// 1 / prod M_i(j w): the sections' inverse (stable: zeros with d_i > 0).
cd InverseSections(const model::Plant& p, double w) {
  const cd s(0.0, w);
  cd g = 1.0;
  for (const model::Mode& md : p.modes) {
    g *= (md.v * md.v) * (s * s + md.c * s + md.omega * md.omega) /
         ((md.omega * md.omega) * (s * s + md.d * s + md.v * md.v));
  }
  return g;
}

Motion Differentiate(const std::vector<double>& y, double fs, const model::Plant& p, double fc) {
  const size_t n = y.size();
  const double T = 1.0 / fs;
  // The straight line through the ends makes the periodic extension continuous;
  // its slope is added back to the velocity.
  const double slope = (y.back() - y.front()) / (static_cast<double>(n - 1) * T);
  std::vector<double> yd(n);
  for (size_t k = 0; k < n; ++k) yd[k] = y[k] - y.front() - slope * static_cast<double>(k) * T;
  const std::vector<cd> Y = Forward(yd);
  std::vector<cd> V(Y.size()), A(Y.size());
  for (size_t k = 0; k < Y.size(); ++k) {
    const double f = static_cast<double>(k) * fs / static_cast<double>(n), w = kTwoPi * f, L = LowPass(f, fc);
    if (L == 0.0) continue;
    const cd jw(0.0, w), X = Y[k] * InverseSections(p, w) * L;
    V[k] = jw * X;
    A[k] = jw * jw * X;
  }
  Motion m{Inverse(V, n), Inverse(A, n)};
  for (double& v : m.v) v += slope;
  return m;
}

// A signal held (or averaged) over each sample interval [jT, (j+1)T) of the
// plant, band-limited by L at the instants jT: times sinc(f T) e^{-j w T/2}
// (the ZOH's continuous-time spectrum, exact below Nyquist).
std::vector<double> HeldBandLimited(const std::vector<double>& g, double fs, double fc) {
  std::vector<cd> G = Forward(g);
  const size_t n = g.size();
  const double T = 1.0 / fs;
  for (size_t k = 0; k < G.size(); ++k) {
    const double f = static_cast<double>(k) * fs / static_cast<double>(n), x = std::numbers::pi * f * T;
    G[k] *= LowPass(f, fc) * (x > 0 ? std::sin(x) / x : 1.0) * std::exp(cd(0.0, -x));
  }
  return Inverse(G, n);
}

// The motor torque in the plant's time: U_j = u_{j - D} (0 before the log).
std::vector<double> PlantTime(const std::vector<double>& u, int delay) {
  std::vector<double> U(u.size(), 0.0);
  for (size_t j = static_cast<size_t>(delay); j < u.size(); ++j) U[j] = u[j - delay];
  return U;
}

// The rigid body with friction, simulated exactly (events at v = 0) from the
// measured torque: per sample interval the average of sign(v) while moving
// and the fraction of it spent moving. Its velocity converges to the
// device's whatever the start (the friction is monotone in v: two solutions'
// difference decays), so it gives the switching instants at full bandwidth,
// free of the encoder's noise.
struct Sliding {
  std::vector<double> sign, moving;
};

Sliding SimulateRigidBody(const std::vector<double>& U, double fs, double m, double b, double fc, double offset,
                          double v0) {
  Sliding s{std::vector<double>(U.size()), std::vector<double>(U.size())};
  const double T = 1.0 / fs, tau = m / b;
  double v = v0;
  for (size_t j = 0; j < U.size(); ++j) {
    const double F = U[j] + offset;
    double left = T, sg = 0.0, mv = 0.0;
    while (left > 0) {
      if (v == 0.0 && std::abs(F) <= fc) break;  // stuck for the rest of the interval
      const double dir = v != 0.0 ? (v > 0 ? 1.0 : -1.0) : (F > 0 ? 1.0 : -1.0);
      const double v_inf = (F - fc * dir) / b;
      double dt = left;
      bool stops = false;
      if (v != 0.0 && v_inf * dir < 0.0) {
        const double t_stop = tau * std::log((v - v_inf) / (-v_inf));
        if (t_stop < left) { dt = t_stop; stops = true; }
      }
      v = stops ? 0.0 : v_inf + (v - v_inf) * std::exp(-dt / tau);
      sg += dir * dt;
      mv += dt;
      left -= dt;
    }
    s.sign[j] = sg / T;
    s.moving[j] = mv / T;
  }
  return s;
}

struct Idim {
  double b = 0, fc = 0, offset = 0, b_std = 0, fc_std = 0, offset_std = 0;
  int rows = 0, decimation = 1;
};

// Step 2: L[U mv] - m a = b v + F_c L[sign v] - offset L[mv] over the kept rows
// (mv the moving fraction: at rest friction balances the torque exactly).
Idim SolveIdim(const Motion& mo, const std::vector<double>& lhs_u, const std::vector<double>& sign,
               const std::vector<double>& moving, double m, double fs, double fc, double min_speed_fraction) {
  const size_t n = mo.v.size();
  double v2 = 0;
  for (double v : mo.v) v2 += v * v;
  const double v_min = min_speed_fraction * std::sqrt(v2 / static_cast<double>(n));
  Idim r;
  r.decimation = std::max(1, static_cast<int>(std::floor(fs / (2.0 * 1.5 * fc))));
  const size_t edge = static_cast<size_t>(std::ceil(4.0 * fs / fc));
  std::vector<size_t> rows;
  for (size_t k = edge; k + edge < n; k += r.decimation) {
    if (std::abs(mo.v[k]) >= v_min) rows.push_back(k);
  }
  if (rows.size() < 200) {
    throw InputError(Num("the friction fit has %.0f usable samples (moving, away from the log's ends, every %.0f-th): "
                         "at least 200 are needed; record a longer log or drive the device harder",
                         static_cast<double>(rows.size()), r.decimation));
  }
  Eigen::MatrixXd X(rows.size(), 3);
  Eigen::VectorXd z(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    const size_t k = rows[i];
    X(i, 0) = mo.v[k];
    X(i, 1) = sign[k];
    X(i, 2) = -moving[k];
    z(i) = lhs_u[k] - m * mo.a[k];
  }
  // Column scaling keeps the normal equations well conditioned.
  const Eigen::VectorXd scale = X.colwise().norm().transpose().cwiseMax(1e-300);
  const Eigen::MatrixXd Xs = X * scale.cwiseInverse().asDiagonal();
  const Eigen::VectorXd theta = Xs.colPivHouseholderQr().solve(z).cwiseQuotient(scale);
  const Eigen::VectorXd res = z - X * theta;
  const double sigma2 = res.squaredNorm() / std::max<double>(1.0, static_cast<double>(rows.size()) - 3.0);
  const Eigen::MatrixXd cov = sigma2 * (X.transpose() * X).inverse();
  r.b = theta(0);
  r.fc = theta(1);
  r.offset = theta(2);
  r.b_std = std::sqrt(cov(0, 0));
  r.fc_std = std::sqrt(cov(1, 1));
  r.offset_std = std::sqrt(cov(2, 2));
  r.rows = static_cast<int>(rows.size());
  return r;
}

// The detection's IDIM: sign(v) of the band-limited velocity, no rest phases.
Idim DetectionIdim(const Motion& mo, const std::vector<double>& U, double m, double fs, double fc,
                   double min_speed_fraction) {
  std::vector<double> sg(mo.v.size()), one(mo.v.size(), 1.0);
  for (size_t k = 0; k < sg.size(); ++k) sg[k] = mo.v[k] > 0 ? 1.0 : (mo.v[k] < 0 ? -1.0 : 0.0);
  return SolveIdim(mo, HeldBandLimited(U, fs, fc), HeldBandLimited(sg, fs, fc), one, m, fs, fc, min_speed_fraction);
}

// The simulation-based IDIM with the rigid body (m, b, F_c, offset) of *id
// (b_sim > 0: that b instead, a sharper estimate): simulated, regressed,
// repeated `rounds` times.
Sliding SimulatedIdim(const Motion& mo, const std::vector<double>& U, double m, double b_sim, double fs, double fc,
                      double min_speed_fraction, int rounds, Idim* id) {
  Sliding sl;
  for (int i = 0; i < rounds; ++i) {
    sl = SimulateRigidBody(U, fs, m, std::max(b_sim > 0 ? b_sim : id->b, 1e-9 * m * fs), std::max(id->fc, 0.0), id->offset, mo.v.front());
    std::vector<double> um(U.size());
    for (size_t j = 0; j < U.size(); ++j) um[j] = U[j] * sl.moving[j];
    *id = SolveIdim(mo, HeldBandLimited(um, fs, fc), HeldBandLimited(sl.sign, fs, fc),
                    HeldBandLimited(sl.moving, fs, fc), m, fs, fc, min_speed_fraction);
    // F_c >= 0 (model/friction.h): a negative estimate (noise about 0) is 0,
    // its std kept.
    id->fc = std::max(id->fc, 0.0);
  }
  return sl;
}

// Step 3: the input of the linear part, in the motor's time: on the plant's
// interval j = k + D, (U_j + offset) mv_j - F_c sign_j.
std::vector<double> LinearPartInput(const std::vector<double>& U, const Sliding& sl, int delay, const Idim& id) {
  std::vector<double> out(U.size(), 0.0);
  for (size_t k = 0; k + delay < U.size(); ++k) {
    const size_t j = k + delay;
    out[k] = (U[j] + id.offset) * sl.moving[j] - id.fc * sl.sign[j];
  }
  for (size_t k = U.size() - delay; k < U.size(); ++k) out[k] = out[U.size() - delay - 1];
  return out;
}

// Sets b and its std (log b row and column of the covariance rescaled).
void SetB(double b, double b_std, FitResult* r) {
  const double scale = (b_std / b) / (r->std_errors.b / r->plant.b);
  r->plant.b = b;
  r->std_errors.b = b_std;
  const size_t p = 2 + 4 * r->plant.modes.size();
  if (r->log_covariance.size() != p * p || !std::isfinite(scale)) return;
  for (size_t i = 0; i < p; ++i) {
    r->log_covariance[1 * p + i] *= scale;
    r->log_covariance[i * p + 1] *= scale;
  }
}

// b from whichever of the refit and the IDIM has the smaller std of its own:
// the IDIM sees the whole log's low band (below the response's fmin), the
// refit suffers less from a coarse encoder's noise. The refit's b also
// depends on the F_c removed from its input: friction adds a damping of about
// (b_linear - b) per F_c (the describing function is linear in F_c), so its
// reported std gains (b_linear - b) / F_c x std(F_c) in quadrature (where
// friction's damping is 30 x b, 1 % of F_c is 30 % of b). The IDIM's std
// already holds its correlation with F_c.
void ChooseB(double linear_b, const Idim& id, FitResult* r) {
  if (id.b > 0.0 && id.b_std > 0.0 && id.b_std < r->std_errors.b) {
    SetB(id.b, id.b_std, r);
    return;
  }
  const double slope = id.fc > 0 && linear_b > r->plant.b ? (linear_b - r->plant.b) / id.fc : 0.0;
  SetB(r->plant.b, std::hypot(r->std_errors.b, slope * id.fc_std), r);
}

double AutoCutoff(const model::Plant& p, double fs) {
  double f = 0.04 * fs;
  for (const model::Mode& md : p.modes) f = std::min(f, 0.4 * std::min(md.omega, md.v) / kTwoPi);
  return f;
}

}  // namespace

FrictionFitResult FitFriction(const std::vector<double>& input, const std::vector<double>& output, double fs,
                              const FitResult& linear, const FitOptions& fit_options, const FrictionFitOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
  if (input.size() != output.size()) throw InputError("FitFriction: input and output differ in length");
  if (linear.status != FitStatus::kConverged) throw InputError("FitFriction: the linear fit did not converge");
  FrictionFitResult r;
  r.fit = linear;
  r.linear_b = linear.plant.b;
  r.linear_b_std = linear.std_errors.b;
  r.cutoff_hz = o.cutoff_hz > 0 ? o.cutoff_hz : AutoCutoff(linear.plant, fs);
  if (r.cutoff_hz > 0.3 * fs) throw InputError(Num("FrictionFitOptions::cutoff_hz = %g: must be at most 0.3 x the sample rate (%g Hz)", r.cutoff_hz, 0.3 * fs));
  model::Plant plant = linear.plant;
  const std::vector<double> U = PlantTime(input, plant.delay_samples);
  Motion mo = Differentiate(output, fs, plant, r.cutoff_hz);
  Idim id = DetectionIdim(mo, U, plant.m, fs, r.cutoff_hz, o.min_speed_fraction);
  r.detection_coulomb = id.fc;
  r.detection_coulomb_std = id.fc_std;
  r.detected = id.fc > o.detection_z * id.fc_std;
  auto keep = [&](const Idim& d) {
    r.friction = model::Friction{d.fc, d.fc, d.offset, 0.0, 0.0};
    // The breakaway level is not identified (rest phases are not fitted): unknown.
    r.friction_std = model::Friction{d.fc_std, d.fc_std, d.offset_std, kInf, kInf};
    r.idim_b = d.b;
    r.idim_b_std = d.b_std;
    r.rows_used = d.rows;
    r.decimation = d.decimation;
  };
  keep(id);
  const bool fit_it = o.model == FrictionModel::kCoulomb || (o.model == FrictionModel::kAuto && r.detected);
  if (!fit_it) {
    r.status = FrictionFitStatus::kNotDetected;
    if (r.detected) AddFrictionReason(r, &r.fit);
    return r;
  }
  FitOptions fo = fit_options;
  fo.auto_modes = false;
  fo.auto_delay = false;
  fo.num_modes = static_cast<int>(plant.modes.size());
  fo.delay_samples = plant.delay_samples;
  // The friction-free response can favour another basin than the linear
  // fit's (whose sections friction distorted): converge a few screened starts.
  fo.max_converged_starts = std::max(fo.max_converged_starts, 3);
  FitResult refit;
  for (int it = 0; it < o.iterations; ++it) {
    const double b_sim = it > 0 && refit.std_errors.b < id.b_std ? plant.b : 0.0;
    const Sliding sl = SimulatedIdim(mo, U, plant.m, b_sim, fs, r.cutoff_hz, o.min_speed_fraction, it == 0 ? 6 : 2, &id);
    keep(id);
    fo.init = plant;
    refit = FitModel(ident::EstimateFrequencyResponse(LinearPartInput(U, sl, plant.delay_samples, id), output, fs,
                                                      o.welch), fo);
    r.iterations = it + 1;
    if (refit.status != FitStatus::kConverged) {
      r.status = FrictionFitStatus::kFailed;
      r.message = "the refit of the friction-free response did not converge: " + refit.message;
      return r;
    }
    plant = refit.plant;
      mo = Differentiate(output, fs, plant, r.cutoff_hz);
  }
  r.fit = refit;
  ChooseB(r.linear_b, id, &r.fit);
  r.status = FrictionFitStatus::kFitted;
  r.message = Num("Coulomb friction %.4g +- %.2g", id.fc, id.fc_std) + Num(" (offset %.3g +- %.2g)", id.offset, id.offset_std) +
              Num(" fitted in %.0f rounds; b %.4g", r.iterations, plant.b) + Num(" (the linear-only fit's %.4g)", r.linear_b);
  return r;
}

}  // namespace zwidth::fit
