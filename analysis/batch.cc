#include "analysis/batch.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <tuple>
#include <exception>
#include <limits>
#include <mutex>
#include <new>
#include <thread>
#include <utility>

#include "model/cancel.h"
#include "model/error.h"
#include "model/parallel.h"
#include "build_info.h"

namespace zwidth::analysis {
namespace {

using Cells = std::map<std::string, std::string>;

std::string Full(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// Where a column sits: the fixed ones first, then the rigid body, the modes
// by index, the delays by value; each std after its value.
const std::vector<std::string>& FixedColumns() {
  static const std::vector<std::string> c = {"serial", "logs", "status", "error", "verdict", "verdict_reasons",
                                             "p_min", "outlier", "outlier_d2", "outlier_reasons", "input_hash", "sample_rate_hz",
                                             "units", "fit_quality", "fit_reasons", "warnings", "m", "m_std", "b", "b_std",
                                             "delay_samples", "modes", "friction_status", "friction_topology", "F_c",
                                             "F_c_std", "friction_offset", "friction_offset_std", "linear_only_b",
                                             "linear_only_b_std"};
  return c;
}
const std::vector<std::string>& ModeFields() {
  static const std::vector<std::string> f = {"omega", "omega_std", "c", "c_std", "v", "v_std", "d", "d_std"};
  return f;
}
const std::vector<std::string>& DelayFields() {
  static const std::vector<std::string> f = {"K_cr_at_zero_B", "K_cr_at_zero_B_std", "K_cr_max", "K_cr_max_std",
                                             "B_t", "B_t_std", "B_max", "B_max_std", "B_max_from_zero"};
  return f;
}

// (group, index, field) of a column; unknown columns last, by name.
std::tuple<int, long, long> Rank(const std::string& col) {
  const auto& fixed = FixedColumns();
  if (auto it = std::find(fixed.begin(), fixed.end(), col); it != fixed.end()) return {0, 0, it - fixed.begin()};
  auto indexed = [&](char prefix, const std::vector<std::string>& fields, int group) -> std::optional<std::tuple<int, long, long>> {
    if (col.size() < 3 || col[0] != prefix) return std::nullopt;
    size_t k = prefix == 'm' ? 4 : 1;  // "mode<i>_" or "d<d>_"
    if (prefix == 'm' && col.rfind("mode", 0) != 0) return std::nullopt;
    size_t end = k;
    while (end < col.size() && std::isdigit(static_cast<unsigned char>(col[end]))) ++end;
    if (end == k || end >= col.size() || col[end] != '_' || end - k > 9) return std::nullopt;
    const std::string field = col.substr(end + 1);
    auto it = std::find(fields.begin(), fields.end(), field);
    if (it == fields.end()) return std::nullopt;
    return std::tuple<int, long, long>{group, std::stol(col.substr(k, end - k)), it - fields.begin()};
  };
  if (auto r = indexed('m', ModeFields(), 1)) return *r;
  if (auto r = indexed('d', DelayFields(), 2)) return *r;
  return {3, 0, 0};
}

Cells ErrorRow(const io::BatchEntry& unit, const std::string& hash, const std::string& status, const std::string& what) {
  return {{"serial", unit.serial}, {"logs", unit.path}, {"status", status}, {"error", what}, {"input_hash", hash}};
}

// Columns a spec may name: the rigid body's and the modes' numbers and the figures per delay.
bool SpecColumn(const std::string& col, const std::vector<int>& delays) {
  if (col == "m" || col == "b" || col == "F_c") return true;
  const auto [group, index, field] = Rank(col);
  if (group == 1) return index >= 1 && field % 2 == 0;  // a value, not its std
  if (group == 2) {
    return field % 2 == 0 && std::find(delays.begin(), delays.end(), index) != delays.end();
  }
  return false;
}

}  // namespace

BatchSpec ParseBatchSpec(const std::string& text, const std::vector<int>& delays) {
  BatchSpec s;
  s.text = text;
  const size_t ge = text.find(">="), le = text.find("<=");
  const size_t at = ge != std::string::npos ? ge : le;
  auto bad = [&](const std::string& what) {
    std::string d;
    for (int x : delays) d += (d.empty() ? "" : ", ") + std::string("d") + std::to_string(x) + "_K_cr_max";
    return InputError("spec '" + text + "': " + what + "; write COLUMN>=BOUND or COLUMN<=BOUND with a column of "
                      "the table: m, b, F_c, mode<i>_{omega,c,v,d}, d<delay>_{K_cr_at_zero_B,K_cr_max,B_t,B_max,"
                      "B_max_from_zero} for a delay of the run (" + d + ")");
  };
  if (at == std::string::npos || (ge != std::string::npos && le != std::string::npos)) throw bad("no single >= or <=");
  s.at_least = at == ge;
  s.column = text.substr(0, at);
  while (!s.column.empty() && s.column.back() == ' ') s.column.pop_back();
  while (!s.column.empty() && s.column.front() == ' ') s.column.erase(0, 1);
  if (!SpecColumn(s.column, delays)) throw bad("no column '" + s.column + "'");
  const std::string num = text.substr(at + 2);
  char* end = nullptr;
  s.bound = std::strtod(num.c_str(), &end);
  while (end && *end == ' ') ++end;
  if (num.empty() || end == num.c_str() || *end != '\0' || !std::isfinite(s.bound)) {
    throw bad("the bound '" + num + "' is not a finite number");
  }
  return s;
}

void ApplySpecs(const std::vector<BatchSpec>& specs, Cells* cells) {
  Cells& c = *cells;
  for (auto it = c.begin(); it != c.end();) {
    const bool verdict = it->first == "verdict" || it->first == "verdict_reasons" || it->first.rfind("p_", 0) == 0;
    it = verdict ? c.erase(it) : std::next(it);
  }
  if (specs.empty()) return;
  if (c["status"] != "ok") {
    c["verdict"] = "error";
    return;
  }
  double p_min = 1.0;
  std::string reasons;
  for (const BatchSpec& s : specs) {
    auto value_of = [&](const std::string& col) {
      auto it = c.find(col);
      return it == c.end() || it->second.empty() ? std::numeric_limits<double>::quiet_NaN() : std::strtod(it->second.c_str(), nullptr);
    };
    const double v = value_of(s.column), sd = value_of(s.column + "_std");
    const bool met = s.at_least ? v >= s.bound : v <= s.bound;  // false for nan (a mode the unit lacks)
    double p = met ? 1.0 : 0.0;
    if (std::isfinite(v) && std::isfinite(sd) && sd > 0) {
      const double z = (s.at_least ? v - s.bound : s.bound - v) / sd;
      p = 0.5 * std::erfc(-z / std::sqrt(2.0));  // Phi(z)
    }
    p_min = std::min(p_min, p);
    c["p_" + s.column + (s.at_least ? "_min" : "_max")] = Full(p);
    if (p < 0.95) {
      char b[160];
      std::snprintf(b, sizeof b, " (value %.6g, std %.3g, P = %.3g)", v, sd, p);
      reasons += (reasons.empty() ? "" : "; ") + s.text + (met ? " met within noise" : " not met") + b;
    }
  }
  c["verdict"] = p_min >= 0.95 ? "pass" : p_min <= 0.05 ? "fail" : "marginal";
  // A poor fit's values (and their std) are not to be trusted to pass a unit: it fails on its fit.
  if (auto q = c.find("fit_quality"); q != c.end() && q->second == "poor") {
    c["verdict"] = "fail";
    reasons = "the fit is poor (" + c["fit_reasons"] + "): its values cannot pass a unit" +
              (reasons.empty() ? "" : "; " + reasons);
  }
  c["verdict_reasons"] = reasons;
  c["p_min"] = Full(p_min);
}

std::vector<BatchSpec> DesignSpecs(const io::Design& design, const ReferenceStability& design_zwidth) {
  std::vector<BatchSpec> out;
  const model::Plant& p = design.model.plant;
  for (const io::DesignTolerance& t : design.tolerances) {
    double value = std::numeric_limits<double>::quiet_NaN();
    if (t.is_figure) {
      const auto d = std::find(design_zwidth.delays.begin(), design_zwidth.delays.end(), t.delay);
      if (d == design_zwidth.delays.end()) {
        std::string list;
        for (int x : design_zwidth.delays) list += (list.empty() ? "" : ",") + std::to_string(x);
        throw InputError(t.where + ": delay " + std::to_string(t.delay) + " is not one of the run's RunOptions::delays " + list +
                         "; add it to RunOptions::delays");
      }
      const stability::DelaySummary& s = design_zwidth.summaries[d - design_zwidth.delays.begin()];
      value = t.figure == "K_cr_at_zero_B" ? s.K_cr_at_zero_B : t.figure == "K_cr_max" ? s.K_cr_max
            : t.figure == "B_t" ? s.B_t : t.figure == "B_max" ? s.B_max : s.B_max_from_zero;
    } else if (t.column == "m" || t.column == "b") {
      value = t.column == "m" ? p.m : p.b;
    } else {
      const size_t us = t.column.find('_');
      const size_t i = std::stoul(t.column.substr(4, us - 4));
      if (i > p.modes.size()) {
        throw InputError(t.where + ": the design's model has " + std::to_string(p.modes.size()) + " mode(s), no " +
                         t.column + "; name a mode it has, or give min/max");
      }
      const model::Mode& m = p.modes[i - 1];
      const std::string f = t.column.substr(us + 1);
      value = f == "omega" ? m.omega : f == "c" ? m.c : f == "v" ? m.v : m.d;
    }
    const bool around = t.relative || t.absolute;
    if (around && !std::isfinite(value)) {
      throw InputError(t.where + ": the design's " + t.column + " is " + Full(value) +
                       ", no value to be relative to; give min and/or max");
    }
    const double half = t.relative ? *t.relative * std::abs(value) : t.absolute ? *t.absolute : 0.0;
    const std::optional<double> lo = around ? std::optional<double>(value - half) : t.min;
    const std::optional<double> hi = around ? std::optional<double>(value + half) : t.max;
    char how[160] = "";
    if (t.relative) std::snprintf(how, sizeof how, ", design %.6g +- %.3g %%", value, 100 * *t.relative);
    if (t.absolute) std::snprintf(how, sizeof how, ", design %.6g +- %.6g", value, *t.absolute);
    for (int side = 0; side < 2; ++side) {
      const std::optional<double>& b = side == 0 ? lo : hi;
      if (!b) continue;
      BatchSpec s;
      s.column = t.column;
      s.at_least = side == 0;
      s.bound = *b;
      char bound[40];
      std::snprintf(bound, sizeof bound, "%.6g", *b);
      s.text = t.column + (s.at_least ? ">=" : "<=") + bound + " (" + t.where + how + ")";
      out.push_back(std::move(s));
    }
  }
  return out;
}

bool BatchOptions::IsValid(std::string* why) const {
  if (threads < 0) {
    *why = "BatchOptions::threads = " + std::to_string(threads) + ": must be >= 0 (0 for the cores available)";
    return false;
  }
  for (size_t i = 0; i < specs.size(); ++i) {
    for (size_t k = 0; k < i; ++k) {
      if (specs[k].column == specs[i].column && specs[k].at_least == specs[i].at_least) {
        *why = "BatchOptions::specs: '" + specs[k].text + "' and '" + specs[i].text + "' both bound " +
               specs[i].column + (specs[i].at_least ? " from below" : " from above") +
               "; keep one (a spec beside a design's tolerance on the same column, or a spec given twice)";
        return false;
      }
    }
  }
  return run.IsValid(why);
}

double BatchProgress::rate_per_s() const {
  return computed > 0 && elapsed_s > 0 ? static_cast<double>(computed) / elapsed_s
                                       : std::numeric_limits<double>::quiet_NaN();
}
double BatchProgress::seconds_left() const { return static_cast<double>(total - done) / rate_per_s(); }

Cells BatchRowOf(const io::BatchEntry& unit, const std::string& input_hash, const RunAnalysis& a) {
  Cells c = ErrorRow(unit, input_hash, "ok", "");
  const io::ModelFile& mf = a.input.model;
  const model::Plant& p = mf.plant;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::optional<model::Plant>& s = mf.std_errors;
  c["sample_rate_hz"] = Full(a.input.response.frf.sample_rate_hz);
  c["units"] = model::Units(mf.linear).word;  // rotary | linear: what the values' units are
  c["fit_quality"] = fit::ToString(a.input.fit.quality);
  std::string reasons, warnings;
  for (const fit::QualityReason& q : a.input.fit.reasons) reasons += (reasons.empty() ? "" : ";") + q.code;
  for (const std::string& w : a.input.fit.warnings) warnings += (warnings.empty() ? "" : " | ") + w;
  c["fit_reasons"] = reasons;
  c["warnings"] = warnings;
  c["m"] = Full(p.m);
  c["m_std"] = Full(s ? s->m : nan);
  c["b"] = Full(p.b);
  c["b_std"] = Full(s ? s->b : nan);
  c["delay_samples"] = std::to_string(p.delay_samples);
  c["modes"] = std::to_string(p.modes.size());
  // The friction as model.json carries it (the model's friction and std, fit.friction's record).
  const fit::FrictionFitResult& ff = a.input.friction_fit;
  if (ff.status != fit::FrictionFitStatus::kNotRun) {
    c["friction_status"] = fit::ToString(ff.status);
    c["linear_only_b"] = Full(ff.linear_b);
    c["linear_only_b_std"] = Full(ff.linear_b_std);
  }
  if (ff.status == fit::FrictionFitStatus::kFitted) c["friction_topology"] = fit::ToString(ff.topology);
  if (mf.friction || ff.status != fit::FrictionFitStatus::kNotRun) {  // none found: the model's is 0 (no std)
    const bool has_std = mf.friction && mf.friction_std && s;
    c["F_c"] = Full(mf.friction ? mf.friction->MeanCoulomb() : 0.0);
    c["F_c_std"] = Full(has_std ? mf.friction_std->MeanCoulomb() : nan);
    c["friction_offset"] = Full(mf.friction ? mf.friction->offset : 0.0);
    c["friction_offset_std"] = Full(has_std ? mf.friction_std->offset : nan);
  }
  for (size_t i = 0; i < p.modes.size(); ++i) {
    const model::Mode& m = p.modes[i];
    const bool has = s && i < s->modes.size();
    const std::string k = "mode" + std::to_string(i + 1) + "_";
    const double v[] = {m.omega, has ? s->modes[i].omega : nan, m.c, has ? s->modes[i].c : nan,
                        m.v, has ? s->modes[i].v : nan, m.d, has ? s->modes[i].d : nan};
    for (size_t f = 0; f < ModeFields().size(); ++f) c[k + ModeFields()[f]] = Full(v[f]);
  }
  const PlantStability& st = a.stability;
  for (size_t i = 0; i < st.delays.size(); ++i) {
    const stability::DelaySummary& d = st.summaries[i];
    const stability::SummaryStd sd = st.has_std ? st.stds[i] : stability::SummaryStd{};
    const std::string k = "d" + std::to_string(st.delays[i]) + "_";
    const double v[] = {d.K_cr_at_zero_B, sd.K_cr_at_zero_B, d.K_cr_max, sd.K_cr_max, d.B_t, sd.B_t,
                        d.B_max, sd.B_max, d.B_max_from_zero};
    for (size_t f = 0; f < DelayFields().size(); ++f) c[k + DelayFields()[f]] = Full(v[f]);
  }
  return c;
}

std::vector<std::string> BatchColumns(const std::vector<Cells>& rows) {
  std::vector<std::string> cols = FixedColumns();
  for (const Cells& r : rows) {
    for (const auto& [k, v] : r) {
      if (std::find(cols.begin(), cols.end(), k) == cols.end()) cols.push_back(k);
    }
  }
  std::stable_sort(cols.begin(), cols.end(), [](const std::string& a, const std::string& b) {
    const auto ra = Rank(a), rb = Rank(b);
    return ra != rb ? ra < rb : (std::get<0>(ra) == 3 && a < b);
  });
  return cols;
}

io::BatchTable BatchTableOf(const std::vector<std::optional<Cells>>& rows) {
  io::BatchTable t;
  for (const auto& r : rows) if (r) t.rows.push_back(*r);
  t.columns = BatchColumns(t.rows);
  return t;
}

std::string UnitInputHash(const io::BatchEntry& unit, const BatchOptions& options) {
  // The friction model resolved (a default a caller's key need not spell out;
  // tables of batches that fitted no friction are computed again).
  std::string key = options.options_key + "\nzwidth " + build_info::kVersion + "\nfriction " +
                    (options.estimate_fit.friction ? fit::ToString(*options.estimate_fit.friction) : "not looked at");
  for (const auto& [flag, value] : unit.flags) key += "\n--" + flag + "=" + value;
  return io::HashInputs({unit.path}, key);
}

RunAnalysis AnalyseUnit(const io::BatchEntry& unit, const BatchOptions& options, const BatchUnitOptions& unit_options) {
  RunInput in;
  in.logs = {unit.path};
  in.source = unit.path;
  in.reference = options.reference;
  in.reference_name = options.reference_name;
  in.reference_is_table1 = options.reference_is_table1;
  EstimateFitOptions eo = options.estimate_fit;
  eo.reference_thread = false;
  if (unit_options) unit_options(unit, &eo);
  RunOptions run = options.run;
  run.figures = false;
  RunMessages quiet;  // the row holds the unit's warnings, in the caller's words
  quiet.fit.words = options.words;
  return EstimateFitAndAnalyse(std::move(in), eo, std::move(run), options.loop, quiet);
}

BatchResult RunBatch(const std::vector<io::BatchEntry>& units, const BatchOptions& options,
                     const BatchUnitOptions& unit_options, const BatchUnitDone& unit_done,
                     const BatchOnProgress& on_progress) {
  return RunBatchWith(
      units, options, [&](const io::BatchEntry& unit, const RunOptions&) { return AnalyseUnit(unit, options, unit_options); },
      unit_done, on_progress);
}

BatchResult RunBatchWith(const std::vector<io::BatchEntry>& units, const BatchOptions& options,
                         const BatchComputeUnit& compute, const BatchUnitDone& unit_done,
                         const BatchOnProgress& on_progress) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  RunOptions run = options.run;
  run.figures = false;
  std::map<std::string, const Cells*> previous;  // serial -> row
  for (const Cells& r : options.previous.rows) {
    if (auto it = r.find("serial"); it != r.end()) previous[it->second] = &r;
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::optional<Cells>> rows(units.size());
  BatchProgress progress;
  progress.total = units.size();
  std::mutex mu;
  auto finished = [&](size_t i, Cells row, bool resumed) {
    std::lock_guard<std::mutex> lock(mu);
    ++progress.done;
    progress.resumed += resumed;
    progress.computed += !resumed;
    progress.failed += row["status"] != "ok";
    rows[i] = std::move(row);
    progress.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (on_progress) on_progress(progress, rows);
  };
  auto one = [&](size_t i) {
    const io::BatchEntry& unit = units[i];
    const std::string hash = UnitInputHash(unit, options);
    if (auto it = previous.find(unit.serial); it != previous.end() && !hash.empty()) {
      auto h = it->second->find("input_hash");
      if (h != it->second->end() && h->second == hash) {
        Cells row = *it->second;
        ApplySpecs(options.specs, &row);  // judged by today's specs (a design may have changed)
        return finished(i, std::move(row), true);
      }
    }
    Cells row;
    try {
      RunAnalysis a = compute(unit, run);
      if (unit_done) unit_done(unit, a);
      row = BatchRowOf(unit, hash, a);
    } catch (const Cancelled&) {
      throw;  // the batch stops (the rows so far were handed to on_progress)
    } catch (const InputError& e) {
      row = ErrorRow(unit, hash, "input_error", e.what());
    } catch (const ComputationError& e) {
      row = ErrorRow(unit, hash, "computation_error", e.what());
    } catch (const std::bad_alloc&) {
      row = ErrorRow(unit, hash, "computation_error", "out of memory");
    } catch (const std::exception& e) {
      row = ErrorRow(unit, hash, "computation_error", e.what());
    }
    ApplySpecs(options.specs, &row);
    finished(i, std::move(row), false);
  };
  const size_t threads = std::min<size_t>(units.size(), options.threads > 0 ? options.threads : NumThreads());
  std::atomic<size_t> next{0};
  std::exception_ptr stop;  // a cancel (PollCancel) or an error of on_progress: ends the batch
  std::mutex stop_mu;
  auto work = [&] {
    std::optional<ScopedSerialThread> serial;
    if (threads > 1) serial.emplace();
    for (size_t i; (i = next.fetch_add(1)) < units.size();) {
      try {
        PollCancel();
        one(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(stop_mu);
        if (!stop) stop = std::current_exception();
        next.store(units.size());
      }
    }
  };
  {
    std::vector<std::jthread> pool;
    for (size_t t = 1; t < threads; ++t) {
      try {
        pool.emplace_back(work);
      } catch (const std::system_error&) {
        break;  // fewer threads: the ones running do the rest
      }
    }
    work();
  }  // joined
  if (stop) std::rethrow_exception(stop);
  BatchResult out;
  out.table = BatchTableOf(rows);
  out.progress = progress;
  return out;
}

BatchTableSaver::BatchTableSaver(std::string path, double interval_s)
    : path_(std::move(path)), interval_s_(interval_s), last_(std::chrono::steady_clock::now()) {}

void BatchTableSaver::operator()(const BatchProgress& progress,
                                 const std::vector<std::optional<std::map<std::string, std::string>>>& rows) {
  if (progress.done >= progress.total) return;
  if (std::chrono::steady_clock::now() - last_ < std::chrono::duration<double>(interval_s_)) return;
  Save(rows);
}

void BatchTableSaver::Save(const std::vector<std::optional<std::map<std::string, std::string>>>& rows) {
  io::WriteBatchTable(path_, BatchTableOf(rows));
  last_ = std::chrono::steady_clock::now();
}

}  // namespace zwidth::analysis
