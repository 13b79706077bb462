#include "report/run_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "analysis/laps.h"
#include "io/frf_file.h"
#include "io/isolated.h"
#include "io/reference_models.h"
#include "io/stability_files.h"
#include "report/report_internal.h"

namespace zwidth::report {
namespace fs = std::filesystem;
namespace {

using analysis::Laps;

// summary.json: the verdict first, above any Z-width computed from the model.
std::string SummaryJson(const analysis::RunAnalysis& a) {
  const analysis::PlantStability& st = a.stability;
  const analysis::RunInput& in = a.input;
  nlohmann::json summary;
  summary["boundary"] = nlohmann::json::array();
  for (size_t i = 0; i < st.delays.size(); ++i) {
    nlohmann::json e = io::SummaryToJson(st.summaries[i], st.has_std ? &st.stds[i] : nullptr);
    e["delay_samples"] = st.delays[i];
    summary["boundary"].push_back(e);
  }
  summary["B_max_meaning"] = "B_max: the largest B at which some K > 0 is stable (reopened bands included); "
                             "B_max_from_zero: the B where the interval from K = 0+ closes (the paper's B_max)";
  summary["margin_disagreements"] = st.margin_disagreements;
  if (a.comparison) summary["comparison"] = a.comparison->json;
  summary["log"] = in.source;
  summary["logs"] = in.logs;
  summary["estimate"] = ident::ToString(in.response.method);
  summary["whole_record"] = in.whole_record;
  summary["sample_rate_hz"] = in.response.frf.sample_rate_hz;
  summary["num_samples"] = in.total_samples;
  summary["fit"] = in.model.fit;
  summary["reference"] = in.reference ? (in.reference_is_table1 ? "table1 (built in)" : in.reference_name) : "none";
  nlohmann::ordered_json top = {{"fit_quality", fit::ToString(in.fit.quality)},
                                {"fit_quality_reasons", nlohmann::ordered_json::parse(in.model.fit.value("quality_reasons", nlohmann::json::array()).dump())}};
  for (const auto& [k, v] : summary.items()) top[k] = nlohmann::ordered_json::parse(v.dump());
  return top.dump(2) + "\n";
}

void WriteDataFiles(const analysis::RunAnalysis& a, const fs::path& out) {
  io::WriteModelJson((out / "model.json").string(), a.input.model);
  io::WriteFrequencyResponse((out / "frf.csv").string(), a.input.response.frf);
  io::WriteBoundaryCsv((out / "boundary.csv").string(), a.stability.rows);
  io::WriteTextAtomically((out / "summary.json").string(), SummaryJson(a));
}

std::string BodeDat(const analysis::RunAnalysis& a) {
  const ident::CombinedResponse& r = a.input.response;
  const ident::FrequencyResponse& frf = r.frf;
  const analysis::BodeData& bd = a.figures->bode;
  const bool joint = r.method == ident::CombinedMethod::kJoint;
  std::ostringstream b;
  b.precision(10);
  b << "# f_hz |H| phase_deg |G| phase_G_deg coherence" << (joint ? " coherence_ru coherence_ry" : "")
    << " used_by_fit\n";
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    b << frf.f_hz[k] << " " << bd.H_abs[k] << " " << bd.H_phase_deg[k] << " " << bd.G_abs[k] << " "
      << bd.G_phase_deg[k] << " " << frf.coherence[k];
    if (joint) b << " " << r.coherence_ru[k] << " " << r.coherence_ry[k];
    b << " " << (k < frf.used_by_fit.size() && frf.used_by_fit[k] ? 1 : 0) << "\n";
  }
  return b.str();
}

// kcr_*.dat: B K_cr f_cr K_cr_std per delay (blocks apart); the model's from
// the boundary rows (with std), the others' (curves) without.
std::string KcrDat(const analysis::RunAnalysis& a, const std::vector<std::vector<stability::CriticalPoint>>* curves) {
  const analysis::PlantStability& st = a.stability;
  const size_t nB = st.b_grid.size();
  std::ostringstream o;
  o.precision(10);
  for (size_t i = 0; i < st.delays.size(); ++i) {
    for (size_t k = 0; k < nB; ++k) {
      const io::BoundaryRow& row = st.rows[i * nB + k];
      const stability::CriticalPoint& c = curves ? (*curves)[i][k] : row.point;
      o << st.b_grid[k] << " " << c.K_cr << " " << c.f_cr_hz << " "
        << (curves ? std::numeric_limits<double>::quiet_NaN() : row.K_cr_std) << "\n";
    }
    o << "\n\n";
  }
  return o.str();
}

// The stable set: one vertical segment per (B, interval), +inf drawn at
// *k_clip = 1.2 x the largest finite K of the table.
std::string RegionDat(const analysis::PlantStability& st, double* k_clip_out) {
  double k_clip = 0.0;
  for (const auto& r : st.rows) {
    for (const auto& iv : r.intervals) k_clip = std::max(k_clip, std::isfinite(iv.K_hi) ? iv.K_hi : iv.K_lo);
  }
  k_clip = k_clip > 0.0 ? 1.2 * k_clip : 1.0;
  *k_clip_out = k_clip;
  const size_t nB = st.b_grid.size();
  std::ostringstream o;
  o.precision(10);
  for (size_t i = 0; i < st.delays.size(); ++i) {
    o << "# delay " << st.delays[i] << ": B K_lo K_hi (K_hi = +inf drawn at " << k_clip << ")\n";
    bool any = false;
    for (size_t k = 0; k < nB; ++k) {
      for (const auto& iv : st.rows[i * nB + k].intervals) {
        o << st.b_grid[k] << " " << iv.K_lo << " " << std::min(iv.K_hi, k_clip) << "\n";
        any = true;
      }
    }
    if (!any) o << "nan nan nan\n";
    o << "\n\n";
  }
  return o.str();
}

// loop_region.dat (B which K_lo K_hi; which 0 raw, 1 filtered; +inf drawn at
// k_clip) and loop_passive.dat (B K_P raw, K_P filtered). Returns the loop
// figure's upper K.
double WriteLoopDat(const analysis::FigureData& f, double k_clip, const fs::path& fig) {
  double k_clip_loop = k_clip;
  std::ostringstream o, q;
  o.precision(10);
  q.precision(10);
  for (const analysis::LoopFigureDelay& d : f.loop) {
    for (size_t k = 0; k < d.B.size(); ++k) {
      for (int which = 0; which < 2; ++which) {
        for (const auto& iv : (which ? d.filtered : d.raw)[k]) {
          o << d.B[k] << " " << which << " " << iv.K_lo << " " << std::min(iv.K_hi, k_clip) << "\n";
          if (std::isfinite(iv.K_hi)) k_clip_loop = std::max(k_clip_loop, 1.05 * iv.K_hi);
        }
      }
      q << d.B[k] << " " << d.K_passive_raw[k] << " " << d.K_passive_filtered[k] << "\n";
    }
    o << "nan nan nan nan\n\n\n";
    q << "\n\n";
  }
  io::WriteTextAtomically((fig / "loop_region.dat").string(), o.str());
  io::WriteTextAtomically((fig / "loop_passive.dat").string(), q.str());
  return k_clip_loop;
}

// Table II (the paper's relay points) at the delays drawn.
std::string Table2Dat(const std::vector<int>& delays) {
  std::ostringstream t2;
  for (const io::Table2Point& p : io::Table2Points()) {
    if (std::find(delays.begin(), delays.end(), p.delay_samples) == delays.end()) continue;
    t2 << p.delay_samples << " " << p.B << " " << p.K_cr << " " << p.f_cr_hz << "\n";
  }
  return t2.str();
}

// figures/: the .dat files and figures.gp.
void WriteFigureFiles(const analysis::RunAnalysis& a, const fs::path& fig, bool png) {
  const analysis::FigureData& f = *a.figures;
  fs::create_directories(fig);
  io::WriteTextAtomically((fig / "bode.dat").string(), BodeDat(a));
  io::WriteTextAtomically((fig / "kcr_model.dat").string(), KcrDat(a, nullptr));
  if (a.input.reference) io::WriteTextAtomically((fig / "kcr_reference.dat").string(), KcrDat(a, &f.kcr_reference));
  io::WriteTextAtomically((fig / "kcr_rigid.dat").string(), KcrDat(a, &f.kcr_rigid));
  double k_clip = 1.0;
  io::WriteTextAtomically((fig / "region_model.dat").string(), RegionDat(a.stability, &k_clip));
  const double k_clip_loop = WriteLoopDat(f, k_clip, fig);
  const bool table1 = a.input.reference && a.input.reference_is_table1;  // drawn only beside Table I
  if (table1) io::WriteTextAtomically((fig / "table2.dat").string(), Table2Dat(a.options.delays));
  const FigureScriptOptions so{a.options.delays, a.input.response.method,
                               a.input.response.method == ident::CombinedMethod::kJoint,
                               a.options.linear, a.input.reference.has_value(), table1,
                               k_clip, k_clip_loop, a.options.report_filter_hz, png};
  io::WriteTextAtomically((fig / "figures.gp").string(), FigureScript(so));
}

// gnuplot started with an argument vector in the figures folder: no shell, so
// no folder name is ever interpreted. 127: not installed.
FiguresStatus DrawFigures(const fs::path& fig) {
  const int rc = io::RunProgram({"gnuplot", "figures.gp"}, fig.string(), (fig / "gnuplot.log").string());
  return rc == 0 ? FiguresStatus::kDrawn : rc == 127 ? FiguresStatus::kGnuplotMissing : FiguresStatus::kGnuplotFailed;
}

}  // namespace

RunReport WriteRunReport(const analysis::RunAnalysis& a, const io::OutputFolder& folder,
                         const RunReportOptions& options) {
  const fs::path out(folder.temp_path());
  RunReport r;
  Laps laps;
  WriteDataFiles(a, out);
  r.stages.push_back({"write outputs", laps.Lap()});
  if (a.figures) {
    const fs::path fig = out / "figures";
    WriteFigureFiles(a, fig, options.png);
    r.stages.push_back({"figure files", laps.Lap()});
    r.figures = FiguresStatus::kNotDrawn;
    if (options.draw_figures) {
      r.figures = DrawFigures(fig);
      if (r.figures != FiguresStatus::kGnuplotMissing) r.stages.push_back({"figures (gnuplot)", laps.Lap()});
    }
  }
  io::WriteTextAtomically((out / "report.html").string(), RunHtml(a, r.figures == FiguresStatus::kDrawn, options.fit_report));
  return r;
}

}  // namespace zwidth::report
