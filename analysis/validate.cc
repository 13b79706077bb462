#include "analysis/validate.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numbers>

#include <Eigen/QR>

#include "fit/fit.h"
#include "model/error.h"
#include "model/state_space.h"

namespace zwidth::analysis {
namespace {

std::string Fmt(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buf[400];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

// The model's output for the log's input with the initial state x0 and a
// constant input offset beta chosen by least squares: y_sim = y_u + O x0 + s beta,
// O's row k = C A^k (the free responses), s the response to a unit constant
// input. Columns scaled to unit norm before a column-pivoting QR: the rigid
// body's columns (a constant and a ramp) and a fast mode's (gone after a few
// samples) differ by many orders of magnitude. The least squares uses the
// first kMaxEntries / (n + 1) samples at most (2^20 for a 2-mode model; the
// initial state shows early, and the rigid body's constant and ramp persist),
// so its memory is bounded; the simulation covers the whole log.
constexpr size_t kMaxEntries = size_t{1} << 23;  // 64 MiB of the least-squares matrix

std::vector<double> SimulateWithInitialState(const model::StateSpace& sd, const std::vector<double>& u,
                                             const std::vector<double>& y, double* beta) {
  const size_t N = u.size();
  const Eigen::Index n = sd.A.rows();
  const std::vector<double> yu = model::SimulateDiscrete(sd, u);
  const std::vector<double> step = model::SimulateDiscrete(sd, std::vector<double>(N, 1.0));
  const Eigen::Index rows = static_cast<Eigen::Index>(std::min(N, kMaxEntries / static_cast<size_t>(n + 1)));
  Eigen::MatrixXd M(rows, n + 1);
  Eigen::VectorXd rhs(rows);
  Eigen::RowVectorXd r = sd.C;
  for (Eigen::Index k = 0; k < rows; ++k) {
    M.row(k).head(n) = r;
    M(k, n) = step[static_cast<size_t>(k)];
    rhs(k) = y[static_cast<size_t>(k)] - yu[static_cast<size_t>(k)];
    r = r * sd.A;
  }
  Eigen::VectorXd scale = M.colwise().norm().transpose();
  for (Eigen::Index j = 0; j <= n; ++j) scale(j) = scale(j) > 0 ? 1.0 / scale(j) : 1.0;
  M = M * scale.asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(M);
  qr.setThreshold(1e-12);
  const Eigen::VectorXd z = qr.solve(rhs).cwiseProduct(scale);
  *beta = z(n);
  Eigen::VectorXd x = z.head(n);
  std::vector<double> out(N);
  for (size_t k = 0; k < N; ++k) {
    out[k] = yu[k] + sd.C.dot(x) + step[k] * *beta;
    x = sd.A * x;
  }
  return out;
}

double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

// sum_k a_k b_{k + lag} / N over the overlap, means removed.
double Correlation(const std::vector<double>& a, double ma, const std::vector<double>& b, double mb, long lag) {
  const long N = static_cast<long>(a.size());
  double s = 0.0;
  for (long k = std::max(0L, -lag); k < N && k + lag < N; ++k) s += (a[k] - ma) * (b[k + lag] - mb);
  return s / static_cast<double>(N);
}

void TimeDomain(const model::StateSpace& sd, const io::Log& log, int max_lag, ValidationResult* r) {
  const std::vector<double>& y = log.output;
  r->simulated = SimulateWithInitialState(sd, log.input, y, &r->input_offset);
  std::vector<double> e(y.size());
  for (size_t k = 0; k < y.size(); ++k) e[k] = y[k] - r->simulated[k];
  const double my = Mean(y), me = Mean(e), mu = Mean(log.input);
  double ne = 0.0, ny = 0.0;
  for (size_t k = 0; k < y.size(); ++k) {
    ne += e[k] * e[k];
    ny += (y[k] - my) * (y[k] - my);
  }
  r->fit_percent = ny > 0 ? 100.0 * (1.0 - std::sqrt(ne / ny)) : 0.0;
  const double ree0 = Correlation(e, me, e, me, 0), ruu0 = Correlation(log.input, mu, log.input, mu, 0);
  r->correlation_bound = 2.576 / std::sqrt(static_cast<double>(y.size()));
  for (long k = 0; k <= max_lag; ++k) {
    const double c = ree0 > 0 ? Correlation(e, me, e, me, k) / ree0 : 0.0;
    r->residual_autocorrelation.push_back(c);
    if (k > 0 && std::abs(c) > r->correlation_bound) ++r->autocorrelation_outside;
  }
  const double norm = std::sqrt(ree0 * ruu0);
  for (long k = -max_lag; k <= max_lag; ++k) {
    const double c = norm > 0 ? Correlation(log.input, mu, e, me, k) / norm : 0.0;
    r->cross_correlation.push_back(c);
    if (std::abs(c) > r->correlation_bound) ++r->cross_correlation_outside;
  }
}

void FrequencyDomain(const model::StateSpace& sd, const io::Log& log, const ValidateOptions& o,
                     ValidationResult* r) {
  r->response = ident::EstimateFrequencyResponse(log.input, log.output, log.info.sample_rate_hz, o.welch);
  const ident::FrequencyResponse& frf = r->response;
  if (frf.num_averages < o.min_averages) {
    throw InputError(Fmt("the log gives %.0f Welch segments of %.0f samples; validate needs at least %.0f for a "
                         "per-bin std: use a longer log or a shorter WelchOptions::window_length",
                         frf.num_averages, frf.window_length, o.min_averages));
  }
  r->band = ident::SelectExcitedBand(frf, o.band);
  const model::DiscreteResponse g(sd);
  const double T = frf.period_s();
  double chi2 = 0.0;
  int used = 0;
  r->normalised_misfit.assign(frf.f_hz.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    if (!r->band.used[k]) continue;
    const std::complex<double> G = g.AtTheta(2 * std::numbers::pi * frf.f_hz[k] * T);
    const double sd_k = std::max(frf.H_std[k], o.relative_std_floor * std::abs(frf.H[k]));
    const double d2 = std::norm(frf.H[k] - G) / (sd_k * sd_k);
    r->normalised_misfit[k] = std::sqrt(d2);
    chi2 += d2;
    ++used;
  }
  if (used == 0) throw InputError("no bin of the log's response has input power and coherence: nothing to compare");
  r->dof = 2 * used;
  r->chi2_per_dof = chi2 / r->dof;
  r->chi2_limit = fit::Chi2PerDofLimit(r->dof, frf);  // the fit verdict's rule
}

void Verdict(ValidationResult* r) {
  if (r->chi2_per_dof > r->chi2_limit) {
    r->reason_codes.push_back("response_misfit");
    r->reasons.push_back(Fmt("the log's frequency response differs from the model's by chi2/dof = %.3g in units of "
                             "its per-bin std, above the limit %.3g (a right model gives about 1 at 8 or more averages, "
                             "n / (n - 2) at fewer: the limit is scaled so)",
                             r->chi2_per_dof, r->chi2_limit));
  }
  if (r->fit_percent < 0) {
    r->reason_codes.push_back("simulation_worse_than_mean");
    r->reasons.push_back(Fmt("the simulated output explains the log less than its mean does (fit %.3g %%)",
                             r->fit_percent));
  }
  r->good = r->reason_codes.empty();
  const double lags = static_cast<double>(r->cross_correlation.size());
  if (r->cross_correlation_outside > 0.05 * lags) {
    r->warnings.push_back(Fmt("residual_correlated_with_input: %.0f of %.0f lags of the residual's cross-correlation "
                              "with the input lie outside the 99 %% bounds +-%.3g: the residual holds error driven by the input (a "
                              "model error, or friction; with many samples and a fine encoder even a right model's "
                              "small parameter errors show here: the response test decides the verdict)",
                              r->cross_correlation_outside, lags, r->correlation_bound));
  }
  const double auto_lags = static_cast<double>(r->residual_autocorrelation.size() - 1);
  if (r->autocorrelation_outside > 0.05 * auto_lags) {
    r->warnings.push_back(Fmt("residual_not_white: %.0f of %.0f lags of the residual's autocorrelation lie outside "
                              "the 99 %% bounds +-%.3g", r->autocorrelation_outside, auto_lags, r->correlation_bound));
  }
}

}  // namespace

bool ValidateOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (!welch.IsValid(why) || !band.IsValid(why)) return false;
  if (!(relative_std_floor >= 0.0 && std::isfinite(relative_std_floor))) {
    return fail("ValidateOptions::relative_std_floor must be finite and >= 0");
  }
  if (max_lag < 1 || max_lag > 10000) return fail("ValidateOptions::max_lag must be in [1, 10000]");
  if (min_averages < 1) return fail("ValidateOptions::min_averages must be >= 1");
  return true;
}

ValidationResult Validate(const io::ModelFile& model, const io::Log& log, const ValidateOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  model.plant.Validate();
  if (log.input.size() != log.output.size() || !(log.info.sample_rate_hz > 0)) {
    throw InputError("validate: the log needs as many input as output samples and a sample rate");
  }
  if (log.input.size() <= static_cast<size_t>(2 * options.max_lag + 1)) {
    throw InputError("validate: the log is shorter than the correlation's lags");
  }
  const double T = log.period_s();
  io::ModelFile m = model;
  io::ConvertDelayToPeriod(&m, T, "the model");  // the delay counted in the log's samples
  const model::StateSpace sd = model::DiscretizeZoh(m.plant, T);
  ValidationResult r;
  FrequencyDomain(sd, log, options, &r);
  TimeDomain(sd, log, options.max_lag, &r);
  Verdict(&r);
  return r;
}

nlohmann::ordered_json ValidationToJson(const ValidationResult& r) {
  nlohmann::ordered_json j;
  j["quality"] = r.good ? "good" : "poor";
  j["quality_reasons"] = r.reason_codes;
  j["reasons"] = r.reasons;
  j["warnings"] = r.warnings;
  j["fit_percent"] = r.fit_percent;
  j["input_offset"] = r.input_offset;
  j["chi2_per_dof"] = r.chi2_per_dof;
  j["dof"] = r.dof;
  j["chi2_limit"] = r.chi2_limit;
  j["band"] = {{"f_lo_hz", r.band.f_lo_hz}, {"f_hi_hz", r.band.f_hi_hz}, {"bins", r.band.num_used},
               {"description", r.band.Describe()}};
  j["welch"] = {{"window_length", r.response.window_length}, {"averages", r.response.num_averages}};
  j["correlation_bound"] = r.correlation_bound;
  j["autocorrelation_outside"] = r.autocorrelation_outside;
  j["cross_correlation_outside"] = r.cross_correlation_outside;
  j["residual_autocorrelation"] = r.residual_autocorrelation;
  j["cross_correlation"] = r.cross_correlation;
  return j;
}

std::string ValidationTraceCsv(const io::Log& log, const ValidationResult& r) {
  std::string s = "t,u,y,y_sim,e\n";
  char line[160];
  const double T = log.period_s();
  for (size_t k = 0; k < r.simulated.size(); ++k) {
    std::snprintf(line, sizeof line, "%.10g,%.10g,%.10g,%.10g,%.6g\n", k * T, log.input[k], log.output[k],
                  r.simulated[k], log.output[k] - r.simulated[k]);
    s += line;
  }
  return s;
}

}  // namespace zwidth::analysis
