#include "apps/fit_support.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "io/reference_models.h"
#include <glog/logging.h>

#include "io/fit_file.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::app {
namespace {

struct Row { std::string name, unit; double value, std; };

std::vector<Row> Rows(const Plant& p, const Plant* s, bool linear = false) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Row> r = {{"m", linear ? "kg" : "kg m^2", p.m, s ? s->m : inf},
                        {"b", linear ? "N s/m" : "N m s/rad", p.b, s ? s->b : inf}};
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const std::string k = std::to_string(i + 1);
    const Mode* e = s ? &s->modes[i] : nullptr;
    r.push_back({"omega" + k, "rad/s", p.modes[i].omega, e ? e->omega : inf});
    r.push_back({"c" + k, "rad/s", p.modes[i].c, e ? e->c : inf});
    r.push_back({"v" + k, "rad/s", p.modes[i].v, e ? e->v : inf});
    r.push_back({"d" + k, "rad/s", p.modes[i].d, e ? e->d : inf});
  }
  return r;
}

}  // namespace

io::ModelFile ReadReference(const std::string& flag, bool* is_table1) {
  const bool t1 = flag == "table1";
  if (is_table1) *is_table1 = t1;
  return t1 ? io::Table1Model() : io::ReadModelJson(flag);
}

void ResolveModesFlag(const std::string& flag, fit::FitOptions* o) {
  if (flag == "auto") { o->auto_modes = true; return; }
  try {
    size_t pos = 0;
    const int n = std::stoi(flag, &pos);
    if (pos != flag.size() || n < 0) throw std::invalid_argument("");
    o->num_modes = n;
    o->auto_modes = false;
  } catch (const std::exception&) {
    throw InputError("--modes '" + flag + "': expected 'auto' or an integer >= 0");
  }
}

void AddFitFlags(CLI::App* cmd, FitFlags* f) {
  cmd->add_option("--modes", f->modes, "resonance/antiresonance sections (0: rigid body) or 'auto' (0..--max-modes, by BIC)")->capture_default_str();
  cmd->add_option("--max-modes", f->o.max_modes, "largest order --modes auto tries, <= 8")->capture_default_str();
  cmd->add_option("--delay-samples", f->delay, "input delay [samples] or 'auto' (searched around the phase slope's)")->capture_default_str();
  cmd->add_option("--max-delay", f->o.max_auto_delay, "largest delay --delay-samples auto tries [samples]")->capture_default_str();
  cmd->add_flag("--allow-short", f->o.allow_few_averages, "fit a response of fewer than 3 Welch segments anyway (judged poor)");
  cmd->add_option("--min-input-power", f->o.band.min_input_power_ratio,
                  "bins used only where the input PSD is at least this fraction of its 99th percentile")->capture_default_str();
  cmd->add_option("--min-coherence", f->o.band.min_coherence, "bins with lower coherence are not used")->capture_default_str();
}

void FitFlags::Resolve(double fmin_hz, double fmax_hz) {
  ResolveModesFlag(modes, &o);
  ResolveDelayFlag(delay, &o);
  o.band.fmin_hz = fmin_hz;
  o.band.fmax_hz = fmax_hz;
  std::string why;
  if (!o.IsValid(&why)) throw InputError(why);
}

std::string FitReport(const fit::FitResult& r) {
  std::ostringstream os;
  os << "band: " << r.band.Describe() << "\n";
  if (!r.delay_choice.empty()) os << r.delay_choice << "\n";
  if (!r.order_table.empty()) {
    char line[400];
    os << "order search (stabilisation table; * = pole within 2% of one at the order below):\n";
    std::snprintf(line, sizeof line, "  %5s %10s %12s  %s\n", "modes", "chi2/dof", "BIC", "poles [Hz]; rejected because");
    os << line;
    for (const fit::OrderTrial& t : r.order_table) {
      std::string poles;
      for (size_t i = 0; i < t.pole_hz.size(); ++i) {
        char p[40];
        std::snprintf(p, sizeof p, "%s%.4g%s", i ? " " : "", t.pole_hz[i], t.persists[i] ? "*" : "");
        poles += p;
      }
      if (!t.spurious.empty()) poles += (poles.empty() ? "" : "; ") + t.spurious.front();
      if (t.spurious.size() > 1) poles += " (+" + std::to_string(t.spurious.size() - 1) + " more)";
      std::snprintf(line, sizeof line, "  %5d %10.4g %12.6g  %s\n", t.num_modes, t.chi2_per_dof, t.bic, poles.c_str());
      os << line;
    }
    os << "chosen: " << r.order_choice << "\n";
  }
  os << "quality: " << fit::ToString(r.quality) << "\n";
  for (const fit::QualityReason& q : r.reasons) os << "  - " << q.message << "\n    advice: " << q.advice << "\n";
  return os.str();
}

void ResolveDelayFlag(const std::string& flag, fit::FitOptions* o) {
  if (flag == "auto") { o->auto_delay = true; return; }
  try {
    size_t pos = 0;
    const int d = std::stoi(flag, &pos);
    if (pos != flag.size() || d < 0) throw std::invalid_argument("");
    o->delay_samples = d;
  } catch (const std::exception&) {
    throw InputError("--delay-samples '" + flag + "': expected 'auto' or an integer >= 0");
  }
}

io::ModelFile FitToModelFile(const ident::FrequencyResponse& frf, const fit::FitOptions& o,
                             const std::string& source, fit::FitResult* out) {
  // Ceres logs through glog (e.g. "Covariance matrix is near rank
  // deficient"): keep it off the terminal; what matters reaches the fit's own
  // warnings and quality reasons.
  FLAGS_minloglevel = google::GLOG_FATAL;
  const fit::FitResult r = fit::FitModel(frf, o);
  if (out) *out = r;
  for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (r.status != fit::FitStatus::kConverged) throw ComputationError(r.message);
  return io::FittedModelFile(r, frf, o, source);
}

std::string ParameterTable(const io::ModelFile& mf, bool linear) {
  std::ostringstream os;
  char line[160];
  std::snprintf(line, sizeof line, "%-8s %14s %12s  %s\n", "param", "value", "std", "unit");
  os << line;
  for (const Row& r : Rows(mf.plant, mf.std_errors ? &*mf.std_errors : nullptr, linear)) {
    std::snprintf(line, sizeof line, "%-8s %14.6g %12.3g  %s\n", r.name.c_str(), r.value, r.std, r.unit.c_str());
    os << line;
  }
  std::snprintf(line, sizeof line, "%-8s %14d %12s  %s\n", "delay", mf.plant.delay_samples, "", "samples");
  os << line;
  return os.str();
}

nlohmann::json CompareModels(const io::ModelFile& model, const io::ModelFile& ref,
                             const std::vector<int>& delays, double T, std::string* text,
                             const std::vector<stability::DelaySummary>* model_summaries, bool linear) {
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
  j["stability"] = nlohmann::json::array();
  std::snprintf(line, sizeof line, "\n%-6s %-10s %12s %10s %12s %10s\n", "delay", "model", "K_cr(B=0)", "B_t",
                "K_cr^max", "B_max");
  os << line;
  for (size_t i = 0; i < delays.size(); ++i) {
    const int d = delays[i];
    nlohmann::json e = {{"delay_samples", d}};
    stability::DelaySummary both[2];
    stability::SummaryStd sd;  // of the model's quantities, from its covariance (issue 13)
    for (int which = 0; which < 2; ++which) {
      const Plant& p = which == 0 ? model.plant : ref.plant;
      const stability::DelaySummary s = (which == 0 && model_summaries && model_summaries->size() == delays.size())
                                            ? (*model_summaries)[i]
                                            : stability::ZWidth(p, T, d).Summarize();
      both[which] = s;
      if (which == 0 && !model.log_covariance.empty()) {
        sd = stability::SummaryStdDelta(model.plant, model.log_covariance, T, d, s);
      }
      e[which == 0 ? "model" : "reference"] = io::SummaryToJson(s, which == 0 && !model.log_covariance.empty() ? &sd : nullptr);
      std::snprintf(line, sizeof line, "%-6d %-10s %12.5g %10.5g %12.5g %10.5g\n", d,
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
  if (text) *text = os.str();
  return j;
}

}  // namespace zwidth::app
