#include "analysis/population.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>

#include <Eigen/Dense>

#include "model/error.h"

namespace zwidth::analysis {
namespace {

constexpr double kMadToSigma = 1.482602218505602;  // 1 / Phi^-1(3/4)
const double kNan = std::numeric_limits<double>::quiet_NaN();

std::string Full(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNan;
  const size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + h, v.end());
  const double hi = v[h];
  if (v.size() % 2) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + h));
}

double MadSigma(const std::vector<double>& v, double median) {
  std::vector<double> d;
  d.reserve(v.size());
  for (double x : v) d.push_back(std::abs(x - median));
  return kMadToSigma * Median(std::move(d));
}

// A value column (not a std, not a count): m, b, mode<i>_{omega,c,v,d}, d<d>_<figure>.
bool IsValueColumn(const std::string& c) {
  if (c == "m" || c == "b") return true;
  if (c.size() > 4 && c.ends_with("_std")) return false;
  auto digits_then = [&](size_t k) {
    size_t e = k;
    while (e < c.size() && std::isdigit(static_cast<unsigned char>(c[e]))) ++e;
    return e > k && e < c.size() && c[e] == '_' ? c.substr(e + 1) : std::string();
  };
  if (c.rfind("mode", 0) == 0) {
    const std::string f = digits_then(4);
    return f == "omega" || f == "c" || f == "v" || f == "d";
  }
  if (c.rfind("d", 0) == 0) {
    const std::string f = digits_then(1);
    return f == "K_cr_at_zero_B" || f == "K_cr_max" || f == "B_t" || f == "B_max" || f == "B_max_from_zero";
  }
  return false;
}

double Cell(const std::map<std::string, std::string>& row, const std::string& col) {
  auto it = row.find(col);
  if (it == row.end() || it->second.empty()) return kNan;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  return end && *end == '\0' ? v : kNan;
}

// The normal quantile Phi^-1(q) by bisection on Phi (q in (0, 1)).
double NormalQuantile(double q) {
  double lo = -40, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < q ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

std::string ToString(PopulationStatus s) {
  switch (s) {
    case PopulationStatus::kNotRun: return "not_run";
    case PopulationStatus::kOk: return "ok";
    case PopulationStatus::kTooFewUnits: return "too_few_units";
  }
  return "?";
}

bool PopulationOptions::IsValid(std::string* why) const {
  if (!(outlier_quantile > 0.5 && outlier_quantile < 1.0)) {
    *why = "PopulationOptions::outlier_quantile = " + Full(outlier_quantile) + ": must lie in (0.5, 1), e.g. 0.999";
    return false;
  }
  if (!(reason_z > 0) || !std::isfinite(reason_z)) {
    *why = "PopulationOptions::reason_z = " + Full(reason_z) + ": must be a finite number > 0, e.g. 3";
    return false;
  }
  if (min_units < 3) {
    *why = "PopulationOptions::min_units = " + std::to_string(min_units) + ": must be >= 3";
    return false;
  }
  return true;
}

double ChiSquareQuantile(double q, int k) {
  const double a = 2.0 / (9.0 * k);
  const double t = 1.0 - a + NormalQuantile(q) * std::sqrt(a);
  return k * t * t * t;
}

Population AnalysePopulation(const io::BatchTable& table, const PopulationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  Population p;
  std::vector<size_t> ok;  // rows with status ok
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const auto& r = table.rows[i];
    PopulationUnit u;
    u.serial = r.count("serial") ? r.at("serial") : "";
    u.ok = r.count("status") && r.at("status") == "ok";
    u.distance2 = kNan;
    if (u.ok) ok.push_back(i);
    p.units.push_back(std::move(u));
  }
  p.ok_units = ok.size();
  if (ok.size() < options.min_units) {
    p.status = PopulationStatus::kTooFewUnits;
    p.message = std::to_string(ok.size()) + " unit(s) with status ok, fewer than PopulationOptions::min_units = " +
                std::to_string(options.min_units) + ": no population statistics";
    return p;
  }
  std::vector<double> modes;
  for (size_t i : ok) modes.push_back(Cell(table.rows[i], "modes"));
  p.median_modes = Median(modes);
  size_t poor_fits = 0;
  for (size_t i : ok) poor_fits += table.rows[i].count("fit_quality") && table.rows[i].at("fit_quality") == "poor";
  // Centre and spread per value column.
  for (const std::string& c : table.columns) {
    if (!IsValueColumn(c)) continue;
    std::vector<double> v;
    for (size_t i : ok) {
      const double x = Cell(table.rows[i], c);
      if (std::isfinite(x)) v.push_back(x);
    }
    if (v.empty()) continue;
    PopulationColumn pc;
    pc.column = c;
    pc.units = v.size();
    pc.median = Median(v);
    pc.mad_sigma = MadSigma(v, pc.median);
    pc.min = *std::min_element(v.begin(), v.end());
    pc.max = *std::max_element(v.begin(), v.end());
    // In the distance: held by most units (a mode only some have is no column of the population),
    // spread > 0, and not B_max_from_zero (B_max's twice, with no std).
    pc.in_distance = 2 * pc.units > ok.size() && pc.units >= options.min_units && pc.mad_sigma > 0 &&
                     !c.ends_with("B_max_from_zero");
    if (pc.in_distance) p.distance_columns.push_back(c);
    p.columns.push_back(std::move(pc));
  }
  const size_t k = p.distance_columns.size();
  std::vector<const PopulationColumn*> dc;
  for (const PopulationColumn& c : p.columns) if (c.in_distance) dc.push_back(&c);
  // Standardized values of the units holding every distance column.
  Eigen::MatrixXd y(0, k);
  {
    std::vector<Eigen::VectorXd> rows;
    for (size_t i : ok) {
      Eigen::VectorXd r(k);
      bool all = true;
      for (size_t j = 0; j < k; ++j) {
        r(j) = (Cell(table.rows[i], dc[j]->column) - dc[j]->median) / dc[j]->mad_sigma;
        all = all && std::isfinite(r(j));
      }
      if (all) rows.push_back(r);
    }
    y.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(k));
    for (size_t i = 0; i < rows.size(); ++i) y.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
  }
  // Gnanadesikan-Kettenring correlations, then eigenvalues floored: a positive-definite R.
  Eigen::MatrixXd R = Eigen::MatrixXd::Identity(k, k);
  auto scale = [](const Eigen::VectorXd& v) {
    std::vector<double> x(v.data(), v.data() + v.size());
    const double m = Median(x);
    return MadSigma(x, m);
  };
  for (size_t a = 0; a < k; ++a) {
    for (size_t b = 0; b < a; ++b) {
      const double sp = scale(y.col(a) + y.col(b)), sm = scale(y.col(a) - y.col(b));
      const double den = sp * sp + sm * sm;
      R(a, b) = R(b, a) = den > 0 ? (sp * sp - sm * sm) / den : 0.0;
    }
  }
  if (k > 0) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(R);
    Eigen::VectorXd ev = es.eigenvalues();
    const double floor = 1e-3 * ev.maxCoeff();
    for (Eigen::Index j = 0; j < ev.size(); ++j) ev(j) = std::max(ev(j), floor);
    R = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
  }
  Eigen::VectorXd s(k);
  for (size_t j = 0; j < k; ++j) s(j) = dc[j]->mad_sigma;
  const Eigen::MatrixXd S = s.asDiagonal() * R * s.asDiagonal();
  p.threshold = k > 0 ? ChiSquareQuantile(options.outlier_quantile, static_cast<int>(k)) : kNan;
  for (size_t i : ok) {
    const auto& row = table.rows[i];
    PopulationUnit& u = p.units[i];
    std::vector<std::string> reasons;
    const double m = Cell(row, "modes");
    if (m != p.median_modes) {
      char b[120];
      std::snprintf(b, sizeof b, "%g mode(s) where the population's median is %g", m, p.median_modes);
      reasons.emplace_back(b);
    }
    if (row.count("fit_quality") && row.at("fit_quality") == "poor" && poor_fits * 2 < ok.size()) {
      reasons.push_back("a poor fit (" + (row.count("fit_reasons") ? row.at("fit_reasons") : std::string()) +
                        ") where most of the population's fit: the response has what the model lacks (an extra "
                        "mode, friction, a wrong sign)");
    }
    Eigen::VectorXd r(k), c(k);
    std::string lacks;
    for (size_t j = 0; j < k; ++j) {
      r(j) = Cell(row, dc[j]->column) - dc[j]->median;
      const double sd = Cell(row, dc[j]->column + "_std");
      c(j) = std::isfinite(sd) ? sd * sd : 0.0;
      if (!std::isfinite(r(j))) lacks += (lacks.empty() ? "" : ", ") + dc[j]->column;
    }
    if (!lacks.empty()) {
      reasons.push_back("no finite " + lacks + " (the population's units have it)");
    } else if (k > 0) {
      Eigen::MatrixXd M = S;
      M.diagonal() += c;
      u.distance2 = r.dot(M.llt().solve(r));
      if (u.distance2 > p.threshold) {
        char b[160];
        std::snprintf(b, sizeof b, "robust Mahalanobis D^2 = %.4g > %.4g (chi-square, %zu columns, q = %g)",
                      u.distance2, p.threshold, k, options.outlier_quantile);
        std::vector<std::pair<double, std::string>> z;
        for (size_t j = 0; j < k; ++j) {
          const double zj = r(j) / std::sqrt(M(j, j));
          if (std::abs(zj) > options.reason_z) {
            char e[160];
            std::snprintf(e, sizeof e, "%s = %.5g (median %.5g, z = %+.3g)", dc[j]->column.c_str(),
                          r(j) + dc[j]->median, dc[j]->median, zj);
            z.emplace_back(-std::abs(zj), e);
          }
        }
        std::sort(z.begin(), z.end());
        std::string cols;
        for (size_t q = 0; q < z.size() && q < 4; ++q) cols += (q ? ", " : "") + z[q].second;
        reasons.push_back(std::string(b) + (cols.empty() ? ": no single column beyond |z| " + Full(options.reason_z) +
                                                               " (the combination is unusual)"
                                                         : ": " + cols));
      }
    }
    u.outlier = !reasons.empty();
    for (const std::string& x : reasons) u.reasons += (u.reasons.empty() ? "" : "; ") + x;
  }
  p.status = PopulationStatus::kOk;
  p.message = std::to_string(ok.size()) + " units with status ok, " + std::to_string(k) + " columns in the distance";
  return p;
}

io::BatchTable PopulationTable(const Population& p) {
  io::BatchTable t;
  t.columns = {"column", "units", "median", "mad_sigma", "min", "max", "in_distance"};
  for (const PopulationColumn& c : p.columns) {
    t.rows.push_back({{"column", c.column}, {"units", std::to_string(c.units)}, {"median", Full(c.median)},
                      {"mad_sigma", Full(c.mad_sigma)}, {"min", Full(c.min)}, {"max", Full(c.max)},
                      {"in_distance", c.in_distance ? "yes" : "no"}});
  }
  t.rows.push_back({{"column", "D2_threshold"}, {"units", std::to_string(p.ok_units)}, {"median", Full(p.threshold)}});
  return t;
}

void AddOutlierColumns(const Population& p, io::BatchTable* table) {
  for (const char* c : {"outlier", "outlier_d2", "outlier_reasons"}) {
    if (std::find(table->columns.begin(), table->columns.end(), c) == table->columns.end()) {
      // After the verdict's columns, so that a reader sees both early.
      auto at = std::find(table->columns.begin(), table->columns.end(), "input_hash");
      table->columns.insert(at, c);
    }
  }
  for (size_t i = 0; i < table->rows.size() && i < p.units.size(); ++i) {
    auto& r = table->rows[i];
    const PopulationUnit& u = p.units[i];
    const bool judged = p.status == PopulationStatus::kOk && u.ok;
    r["outlier"] = judged ? (u.outlier ? "yes" : "no") : "";
    r["outlier_d2"] = judged && std::isfinite(u.distance2) ? Full(u.distance2) : "";
    r["outlier_reasons"] = judged ? u.reasons : "";
  }
}

}  // namespace zwidth::analysis
