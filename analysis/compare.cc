#include "analysis/compare.h"

#include <cmath>
#include <numbers>
#include <memory>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "model/units.h"
#include "io/stability_files.h"
#include "model/c_locale.h"
#include "model/error.h"

namespace zwidth::analysis {
namespace {

struct Row { std::string name, unit; double value, std; };

std::vector<Row> Rows(const model::Plant& p, const model::Plant* s, bool linear = false) {
  const double inf = std::numeric_limits<double>::infinity();
  const model::UnitLabels& u = model::Units(linear);
  std::vector<Row> r = {{"m", u.m, p.m, s ? s->m : inf}, {"b", u.b, p.b, s ? s->b : inf}};
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const std::string k = std::to_string(i + 1);
    const model::Mode* e = s ? &s->modes[i] : nullptr;
    r.push_back({"omega" + k, "rad/s", p.modes[i].omega, e ? e->omega : inf});
    r.push_back({"c" + k, "rad/s", p.modes[i].c, e ? e->c : inf});
    r.push_back({"v" + k, "rad/s", p.modes[i].v, e ? e->v : inf});
    r.push_back({"d" + k, "rad/s", p.modes[i].d, e ? e->d : inf});
  }
  return r;
}

// The friction's rows (model.json "friction", its std "std.friction"):
// F_c+ and F_c- (one row F_c when equal) and the offset; none without friction.
std::vector<Row> FrictionRows(const io::ModelFile& mf, bool linear) {
  std::vector<Row> r;
  if (!mf.friction) return r;
  const double inf = std::numeric_limits<double>::infinity();
  const model::Friction& f = *mf.friction;
  const model::Friction* e = mf.friction_std ? &*mf.friction_std : nullptr;
  const std::string unit = model::Units(linear).input;
  if (f.coulomb_pos == f.coulomb_neg) {
    r.push_back({"F_c", unit, f.coulomb_pos, e ? e->coulomb_pos : inf});
  } else {
    r.push_back({"F_c+", unit, f.coulomb_pos, e ? e->coulomb_pos : inf});
    r.push_back({"F_c-", unit, f.coulomb_neg, e ? e->coulomb_neg : inf});
  }
  r.push_back({"offset", unit, f.offset, e ? e->offset : inf});
  return r;
}

// compare's friction lines: the model's friction beside the reference's (0
// when the reference has none).
void CompareFriction(const io::ModelFile& model, const io::ModelFile& ref, bool linear, std::ostringstream& os,
                     nlohmann::json& j) {
  const std::vector<Row> a = FrictionRows(model, linear), b = FrictionRows(ref, linear);
  if (a.empty() && b.empty()) return;
  char line[200];
  os << "friction (model.json 'friction'):\n";
  auto value = [](const std::vector<Row>& rows, const std::string& name) {
    for (const Row& r : rows) if (r.name == name) return r.value;
    return 0.0;
  };
  j["friction"] = nlohmann::json::array();
  for (const Row& r : a.empty() ? b : a) {
    const double mine = value(a, r.name), theirs = value(b, r.name);
    const double sd = a.empty() ? std::numeric_limits<double>::infinity() : r.std;
    std::snprintf(line, sizeof line, "%-8s %12.6g +- %-9.3g %12.6g  %s\n", r.name.c_str(), mine, sd, theirs,
                  r.unit.c_str());
    os << line;
    j["friction"].push_back({{"name", r.name}, {"value", mine}, {"std", io::NumberOrNull(sd)}, {"reference", theirs},
                             {"unit", r.unit}});
  }
}

}  // namespace

std::string ParameterTable(const io::ModelFile& mf, bool linear) {
  linear = linear || mf.linear;  // the model file's units, or the caller's
  const ScopedCLocale c_locale;  // printf's %g writes '.' whatever the caller's locale
  std::ostringstream os;
  char line[160];
  std::snprintf(line, sizeof line, "%-8s %14s %12s  %s\n", "param", "value", "std", "unit");
  os << line;
  std::vector<Row> rows = Rows(mf.plant, mf.std_errors ? &*mf.std_errors : nullptr, linear);
  for (const Row& f : FrictionRows(mf, linear)) rows.push_back(f);
  for (const Row& r : rows) {
    std::snprintf(line, sizeof line, "%-8s %14.6g %12.3g  %s\n", r.name.c_str(), r.value, r.std, r.unit.c_str());
    os << line;
  }
  std::snprintf(line, sizeof line, "%-8s %14d %12s  %s\n", "delay", mf.plant.delay_samples, "", "samples");
  os << line;
  if (mf.encoder_step) {  // read from the log (ident::EncoderStep); the friction predictions use it
    const double q = *mf.encoder_step;
    if (linear) {
      std::snprintf(line, sizeof line, "%-8s %14.6g %12s  %s\n", "encoder", q, "", "m per count (read from the log)");
    } else {
      std::snprintf(line, sizeof line, "%-8s %14.6g %12s  rad per count (read from the log; %.6g per turn)\n",
                    "encoder", q, "", 2.0 * std::numbers::pi / q);
    }
    os << line;
  }
  return os.str();
}

void CheckSameUnits(bool model_linear, const io::ModelFile& reference, const std::string& model_name,
                    const std::string& reference_name) {
  if (model_linear == reference.linear) return;
  auto kind = [](bool linear) {
    const model::UnitLabels& u = model::Units(linear);
    return std::string(u.word) + " (" + u.m + ", " + u.b + ")";
  };
  throw InputError(model_name + " is " + kind(model_linear) + ", " + reference_name + " is " +
                   kind(reference.linear) + ": compare models of one kind (a linear axis with a linear reference "
                   "model, a rotary one with a rotary reference such as Table I; a model file's \"units\" says "
                   "which, and ModelFile::linear gives a fit's)");
}

DelayStability SummarizeDelays(const io::ModelFile& mf, double T, const std::vector<int>& delays) {
  DelayStability r;
  r.has_std = !mf.log_covariance.empty();
  const stability::SampledPlant sp(mf.plant, T);
  std::unique_ptr<stability::PerturbedPlants> pert;
  if (r.has_std) {
    stability::CheckLogCovariance(mf.plant, mf.log_covariance);
    pert = std::make_unique<stability::PerturbedPlants>(stability::SamplePerturbedPlants(mf.plant, T));
  }
  for (int d : delays) {
    const stability::ZWidth z(sp, d);
    r.summaries.push_back(z.Summarize());
    r.stds.push_back(r.has_std ? stability::SummaryStdDelta(z, *pert, mf.log_covariance, d, r.summaries.back())
                               : stability::SummaryStd{});
  }
  return r;
}

ModelComparison CompareModels(const io::ModelFile& model, const io::ModelFile& ref,
                              const std::vector<int>& delays, const DelayStability& ms,
                              const std::vector<stability::DelaySummary>& ref_sums, bool linear) {
  if (ms.summaries.size() != delays.size() || ms.stds.size() != delays.size() || ref_sums.size() != delays.size()) {
    throw std::invalid_argument("CompareModels: one summary per delay expected");
  }
  linear = linear || model.linear;  // the model file's units, or the caller's
  CheckSameUnits(linear, ref, "the model", "the reference");
  const ScopedCLocale c_locale;  // printf's %g writes '.' whatever the caller's locale
  std::ostringstream os;
  nlohmann::json j;
  j["parameters"] = nlohmann::json::array();
  const bool same_shape = model.plant.modes.size() == ref.plant.modes.size();
  char line[200];
  if (same_shape) {
    const auto a = Rows(model.plant, model.std_errors ? &*model.std_errors : nullptr, linear);
    const auto b = Rows(ref.plant, nullptr);
    std::snprintf(line, sizeof line, "%-8s %24s %12s %9s %9s  %s\n", "param", "fitted +- std", "reference",
                  "diff %", "diff/std", "unit");
    os << line;
    for (size_t i = 0; i < a.size(); ++i) {
      const double pct = 100.0 * (a[i].value - b[i].value) / b[i].value;
      const double nsd = std::isfinite(a[i].std) && a[i].std > 0 ? (a[i].value - b[i].value) / a[i].std
                                                                : std::numeric_limits<double>::quiet_NaN();
      std::snprintf(line, sizeof line, "%-8s %12.6g +- %-9.3g %12.6g %9.2f %9.2f  %s\n", a[i].name.c_str(),
                    a[i].value, a[i].std, b[i].value, pct, nsd, a[i].unit.c_str());
      os << line;
      j["parameters"].push_back({{"name", a[i].name}, {"value", a[i].value}, {"std", io::NumberOrNull(a[i].std)},
                                 {"reference", b[i].value}, {"diff_percent", pct},
                                 {"diff_in_std", io::NumberOrNull(nsd)}, {"unit", a[i].unit}});
    }
  } else {
    os << "the models have different numbers of modes (" << model.plant.modes.size() << " vs "
       << ref.plant.modes.size() << "): no per-parameter comparison\n";
  }
  CompareFriction(model, ref, linear, os, j);
  j["stability"] = nlohmann::json::array();
  os << "\ndelay: the loop's; each model adds its own input delay (model " << model.plant.delay_samples
     << ", reference " << ref.plant.delay_samples << " samples)";
  std::snprintf(line, sizeof line, "\n%-6s %-10s %12s %10s %12s %10s\n", "delay", "model", "K_cr(B=0)", "B_t",
                "K_cr^max", "B_max");
  os << line;
  for (size_t i = 0; i < delays.size(); ++i) {
    const int d = delays[i];
    nlohmann::json e = {{"delay_samples", d}};
    stability::DelaySummary both[2];
    // The model's std, from its covariance (issue 13).
    const stability::SummaryStd sd = ms.has_std ? ms.stds[i] : stability::SummaryStd{};
    for (int which = 0; which < 2; ++which) {
      const stability::DelaySummary& s = which == 0 ? ms.summaries[i] : ref_sums[i];
      both[which] = s;
      e[which == 0 ? "model" : "reference"] = io::SummaryToJson(s, which == 0 && ms.has_std ? &sd : nullptr);
      io::AddDelays(&e[which == 0 ? "model" : "reference"], d, (which == 0 ? model : ref).plant.delay_samples);
      char delay[32];
      std::snprintf(delay, sizeof delay, "%d+%d", d, (which == 0 ? model : ref).plant.delay_samples);
      std::snprintf(line, sizeof line, "%-6s %-10s %12.5g %10.5g %12.5g %10.5g\n", delay,
                    which == 0 ? "model" : "reference", s.K_cr_at_zero_B, s.B_t, s.K_cr_max, s.B_max);
      os << line;
    }
    // What the parameter differences do to the Z-width: model - reference, and
    // that in units of the model's std.
    const double dq[4] = {both[0].K_cr_at_zero_B - both[1].K_cr_at_zero_B, both[0].B_t - both[1].B_t,
                          both[0].K_cr_max - both[1].K_cr_max, both[0].B_max - both[1].B_max};
    const double sq[4] = {sd.K_cr_at_zero_B, sd.B_t, sd.K_cr_max, sd.B_max};
    double zq[4];
    for (int q = 0; q < 4; ++q) zq[q] = sq[q] > 0.0 ? dq[q] / sq[q] : std::numeric_limits<double>::quiet_NaN();
    std::snprintf(line, sizeof line, "%-6s %-10s %12.5g %10.5g %12.5g %10.5g\n%-6s %-10s %12.3g %10.3g %12.3g %10.3g\n",
                  "", "difference", dq[0], dq[1], dq[2], dq[3], "", "diff/std", zq[0], zq[1], zq[2], zq[3]);
    os << line;
    const char* keys[4] = {"K_cr_at_zero_B", "B_t", "K_cr_max", "B_max"};
    for (int q = 0; q < 4; ++q) {
      e["difference"][keys[q]] = io::NumberOrNull(dq[q]);
      e["difference_in_std"][keys[q]] = io::NumberOrNull(zq[q]);
    }
    j["stability"].push_back(e);
  }
  return {j, os.str()};
}


}  // namespace zwidth::analysis
