// zwidth run: estimate -> fit -> compare -> boundary -> report, the job a user
// runs on a new device log. Figures are drawn by gnuplot when it is installed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <filesystem>
#include <memory>
#include <fstream>
#include <numbers>
#include <sstream>

#include "analysis/compare.h"
#include "analysis/plant_stability.h"
#include "apps/common.h"
#include "apps/fit_support.h"
#include "apps/loop_flags.h"
#include "io/atomic_file.h"
#include "io/frf_file.h"
#include "io/reference_models.h"
#include "io/isolated.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "model/state_space.h"
#include "stability/haptic_loop.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::app {
namespace fs = std::filesystem;
namespace {

std::string Html(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;"; else if (c == '>') o += "&gt;"; else if (c == '&') o += "&amp;"; else o += c;
  }
  return o;
}

// What the gnuplot script of `run` depends on.
struct FigureScriptOptions {
  std::vector<int> delays;                // loop delays [samples], one panel/curve each
  ident::CombinedMethod method{};         // the estimate's method (Bode title)
  bool joint = false;                     // closed-loop joint estimate: two coherence columns
  bool linear = false;                    // N s/m and N/m labels instead of N m s/rad, N m/rad
  bool have_ref = false;                  // kcr_reference.dat exists
  bool table1 = false;                    // table2.dat exists
  double k_clip = 1.0;                    // upper K of the region figure [N m/rad]
  double k_clip_loop = 1.0;               // upper K of the loop figure [N m/rad]
  double report_filter_hz = 50.0;         // the loop figure's velocity low-pass [Hz]
};

// figures.gp: every figure in SVG and PNG, read from the .dat files beside it.
std::string FigureScript(const FigureScriptOptions& o) {
  std::ostringstream gp;
  gp << "set datafile missing 'nan'\nset grid\nset key outside right\n"
     << "set linetype 1 lc rgb '#1f77b4' lw 2\nset linetype 2 lc rgb '#d62728' lw 2\n"
     << "set linetype 3 lc rgb '#2ca02c' lw 2\nset linetype 4 lc rgb '#9467bd' lw 2\n"
     << "set linetype 5 lc rgb '#ff7f0e' lw 2\nset linetype 6 lc rgb '#8c564b' lw 2\n";
  std::string dl;
  for (size_t i = 0; i < o.delays.size(); ++i) dl += (i ? " " : "") + std::to_string(o.delays[i]);
  gp << "delays = '" << dl << "'\n";
  for (const char* term : {"svg size 900,640 font 'sans,12'", "pngcairo size 900,640 font 'sans,10'"}) {
    const std::string ext = std::string(term).rfind("svg", 0) == 0 ? "svg" : "png";
    gp << "set terminal " << term << "\n";
    gp << "set output 'bode." << ext << "'\nset multiplot layout 2,1 title 'Bode diagram: measured (" << ident::ToString(o.method) << ") and fitted model (exact ZOH) - Fig. 3'\n"
       << "set logscale x\nset logscale y\nset format y '10^{%L}'\nset ylabel 'magnitude [" << (o.linear ? "m/N" : "rad/(N m)") << "]'\nunset xlabel\n"
       << "uc = " << (o.joint ? 9 : 7) << "\n"
       << "plot 'bode.dat' u 1:(column(uc) > 0 ? $2 : NaN) w l lc rgb '#1f77b4' t 'measured, fitted band', "
       << "'' u 1:(column(uc) > 0 ? NaN : $2) w p pt 7 ps 0.25 lc rgb '#bbbbbb' t 'measured, not used', "
       << "'' u 1:4 w l lw 2 lc rgb 'black' t 'fitted model'\n"
       << "unset logscale y\nset format y '%g'\nset ylabel 'phase [deg]'\nset xlabel 'frequency [Hz]'\n"
       << "plot 'bode.dat' u 1:(column(uc) > 0 ? $3 : NaN) w l lc rgb '#1f77b4' t 'measured, fitted band', "
       << "'' u 1:(column(uc) > 0 ? NaN : $3) w p pt 7 ps 0.25 lc rgb '#bbbbbb' t 'measured, not used', "
       << "'' u 1:5 w l lw 2 lc rgb 'black' t 'fitted model'\nunset multiplot\n";
    gp << "set output 'coherence." << ext << "'\nset title 'Magnitude-squared coherence'\nset xlabel 'frequency [Hz]'\nset ylabel 'coherence [-]'\nset yrange [0:1.05]\n"
       << (o.joint ? "plot 'bode.dat' u 1:7 w l lc rgb '#1f77b4' t 'r -> u', '' u 1:8 w l lc rgb '#d62728' t 'r -> y'\n"
                 : "plot 'bode.dat' u 1:6 w l lc rgb '#1f77b4' t 'coherence'\n")
       << "set yrange [*:*]\nunset logscale x\nunset title\n";
    gp << "set output 'kcr." << ext << "'\nset multiplot layout 2,1 title 'Critical stiffness and ultimate frequency vs damping - Fig. 6 / Fig. 10'\n"
       << "set xlabel 'B [" << (o.linear ? "N s/m" : "N m s/rad") << "]'\nset ylabel 'K_{CR} [" << (o.linear ? "N/m" : "N m/rad") << "]'\n"
       << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:2 w l lt i t 'model, d='.word(delays,i)"
       << (o.have_ref ? ", for [i=1:words(delays)] 'kcr_reference.dat' index i-1 u 1:2 w l lt i dt 2 lw 1 t 'reference, d='.word(delays,i)" : "")
       << (o.table1 ? ", 'table2.dat' u 2:3 w p pt 7 ps 0.8 lc rgb 'red' t 'Table II (relay)'" : "") << "\n"
       << "set logscale y\nset ylabel 'f_{CR} [Hz]'\n"
       << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:3 w l lt i t 'model, d='.word(delays,i)"
       << (o.table1 ? ", 'table2.dat' u 2:4 w p pt 7 ps 0.8 lc rgb 'red' t 'Table II (relay)'" : "") << "\nunset logscale y\nunset multiplot\n";
    gp << "set output 'region." << ext << "'\nset multiplot layout " << o.delays.size()
       << ",1 title 'Z-width: stable (B, K) region per delay (shaded), K_{CR}(B) and its +-2 sigma band'\n"
       << "set xlabel 'B [N m s/rad]'\nset ylabel 'K [N m/rad]'\nset yrange [0:" << o.k_clip << "]\n"
       << "do for [i=1:words(delays)] {\n"
       << "  set title 'loop delay '.word(delays,i).' samples'\n"
       << "  plot 'region_model.dat' index i-1 u 1:2:(0):($3-$2) w vectors nohead lc rgb '#9ecae1' t 'stable', "
       << "'kcr_model.dat' index i-1 u 1:($2-2*$4):($2+2*$4) w filledcurves fs transparent solid 0.35 "
       << "lc rgb '#d62728' t 'K_{CR} +- 2 sigma', '' index i-1 u 1:2 w l lw 2 lc rgb '#08306b' t 'K_{CR}(B)'\n"
       << "}\nunset multiplot\nset yrange [*:*]\nunset title\n";
    gp << "set output 'loop." << ext << "'\nset multiplot layout " << o.delays.size()
       << ",1 title 'Stable region without and with a " << o.report_filter_hz
       << " Hz velocity low-pass; passivity boundary K_P(B) (Colgate-Schenkel)'\n"
       << "set xlabel 'B [N m s/rad]'\nset ylabel 'K [N m/rad]'\nset yrange [0:" << o.k_clip_loop << "]\n"
       << "do for [i=1:words(delays)] {\n"
       << "  set title 'loop delay '.word(delays,i).' samples'\n"
       << "  plot 'loop_region.dat' index i-1 u 1:($2==1?$3:1/0):(0):($4-$3) w vectors nohead lc rgb '#fdae6b' t 'stable, filtered', "
       << "'' index i-1 u 1:($2==0?$3:1/0):(0):($4-$3) w vectors nohead lc rgb '#6baed6' t 'stable, raw difference', "
       << "'loop_passive.dat' index i-1 u 1:2 w l lw 2 lc rgb 'black' t 'K_P, raw', '' index i-1 u 1:3 w l lw 2 dt 2 lc rgb '#7f2704' t 'K_P, filtered'\n"
       << "}\nunset multiplot\nset yrange [*:*]\nunset title\n";
    gp << "set output 'rigid." << ext << "'\nset title 'With the vibration modes and without (rigid body only) - Fig. 7'\n"
       << "set xlabel 'B [" << (o.linear ? "N s/m" : "N m s/rad") << "]'\nset ylabel 'K_{CR} [" << (o.linear ? "N/m" : "N m/rad") << "]'\n"
       << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:2 w l lt i t 'with modes, d='.word(delays,i), "
       << "for [i=1:words(delays)] 'kcr_rigid.dat' index i-1 u 1:2 w l lt i dt 2 t 'rigid only, d='.word(delays,i)\nunset title\n";
  }
  return gp.str();
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  struct RunFlags {
    std::vector<std::string> logs;
    std::string outdir, reference, units = "rotary";
    std::vector<int> delays = {2, 4, 8};
    EstimateFlags est;
    FitFlags fit;
    stability::BGridOptions grid;
    bool force = false;
    bool no_figures = false;
    double report_filter_hz = 50.0;
    LoopFlags loop;
  };
  auto f = std::make_shared<RunFlags>();
  CLI::App* cmd = app.add_subcommand("run", "estimate, fit, compare, Z-width boundary and an HTML report");
  cmd->add_option("logs", f->logs, "log files (text, .mat, .h5): runs of one device, spectra averaged")->required();
  cmd->add_option("-o,--output", f->outdir, "output folder: new, or existing and empty (its parent must exist)")->required();
  cmd->add_flag("--force", f->force, "write into a non-empty output folder, replacing zwidth's files there");
  cmd->add_flag("--no-figures", f->no_figures, "no figures/ folder, no gnuplot: the data files and the report only");
  cmd->add_option("--reference", f->reference, "compare with: table1 (the paper's PHANToM, built in) or a model JSON (default: no comparison)");
  cmd->add_option("--delays", f->delays, "loop delays [samples]")->delimiter(',')->capture_default_str();
  f->fit.modes = "auto";  // run chooses the order unless told
  AddFitFlags(cmd, &f->fit);
  cmd->add_option("--b-step", f->grid.b_step, "B step of the boundary [N m s/rad] (wins over --b-points)");
  cmd->add_option("--b-points", f->grid.b_points, "B values of the boundary, 0 to 1.05 x the largest stable B")
      ->capture_default_str();
  cmd->add_option("--report-filter-hz", f->report_filter_hz,
                  "the report's loop figure: region also with a first-order velocity low-pass at this cut-off [Hz]")
      ->capture_default_str();
  AddLoopFlags(cmd, &f->loop);
  AddEstimateFlags(cmd, &f->est);
  AddUnitsFlag(cmd, &f->units);
  cmd->callback([f] {
    f->fit.Resolve(f->est.welch.fmin_hz, f->est.welch.fmax_hz);
    const bool linear = LinearUnits(f->units);
    const std::string source = JoinPaths(f->logs);
    for (int d : f->delays) if (d < 0) throw InputError("--delays must be >= 0");
    bool table1 = false;
    const bool have_ref = !f->reference.empty();
    const io::ModelFile ref = have_ref ? ReadReference(f->reference, &table1) : io::ModelFile{};
    {
      std::string why;
      if (!f->grid.IsValid(&why)) throw InputError(why);
    }
    // Everything is built in a temporary sibling folder and moved into place
    // at the end (io::OutputFolder): a failure or a signal leaves nothing, and
    // two runs into one folder cannot mix.
    io::OutputFolder folder(f->outdir, f->force);
    const fs::path out(folder.temp_path());
    const fs::path final_out(folder.path());
    std::fprintf(stderr, "zwidth run %s -> %s\n", source.c_str(), f->outdir.c_str());
    StageTimer timer;
    const LogsEstimate est = EstimateFromLogs(f->logs, f->est, true);
    ident::FrequencyResponse frf = est.response.frf;
    double t_total = timer.Lap("estimate (read + Welch)");
    fit::FitResult fr;
    const io::ModelFile model = FitToModelFile(frf, f->fit.o, source, &fr);
    frf.used_by_fit = fr.band.used;
    t_total += timer.Lap("fit");
    const double T = 1.0 / frf.sample_rate_hz;
    if (f->loop.hands.size() > 1) throw InputError("run takes one --hand (boundary takes several)");
    const stability::LoopOptions loop = ResolveLoops(f->loop, T)[0];
    // The model's Z-width per delay, computed once for the summary, the
    // comparison, the boundary rows and the figures.
    const analysis::PlantStability st = analysis::AnalysePlantStability(model, T, f->delays, loop, f->grid);
    const std::vector<stability::DelaySummary>& sums = st.summaries;
    const std::vector<stability::SummaryStd>& stds = st.stds;
    const std::vector<double>& bgrid = st.b_grid;
    const std::vector<io::BoundaryRow>& rows = st.rows;
    const bool has_cov = st.has_std;
    const int disagree = st.margin_disagreements;
    const int nB = static_cast<int>(bgrid.size());
    const stability::SampledPlant& sampled = st.sampled;
    nlohmann::json summary;
    summary["boundary"] = nlohmann::json::array();
    for (size_t i = 0; i < f->delays.size(); ++i) {
      nlohmann::json e = io::SummaryToJson(sums[i], has_cov ? &stds[i] : nullptr);
      e["delay_samples"] = f->delays[i];
      summary["boundary"].push_back(e);
    }
    summary["B_max_meaning"] = "B_max: the largest B at which some K > 0 is stable (reopened bands included); "
                               "B_max_from_zero: the B where the interval from K = 0+ closes (the paper's B_max)";
    summary["margin_disagreements"] = disagree;
    t_total += timer.Lap("boundary");
    std::string cmp_text;
    // The reference's Z-width per delay (the paper's loop), for the comparison
    // and the figures.
    std::vector<stability::ZWidth> ref_zs;
    if (have_ref) {  // the paper's loop for both
      const stability::SampledPlant ref_sampled(ref.plant, T);
      std::vector<stability::DelaySummary> ref_sums;
      for (int d : f->delays) {
        ref_zs.emplace_back(ref_sampled, d);
        ref_sums.push_back(ref_zs.back().Summarize());
      }
      const analysis::DelayStability model_st = IsPlainLoop(loop)
                                                    ? analysis::DelayStability{sums, stds, has_cov}
                                                    : analysis::SummarizeDelays(model, T, f->delays);
      analysis::ModelComparison cmp = analysis::CompareModels(model, ref, f->delays, model_st, ref_sums, linear);
      summary["comparison"] = std::move(cmp.json);
      cmp_text = std::move(cmp.text);
      t_total += timer.Lap("compare (reference Z-width)");
    }
    Plant rigid = model.plant;
    rigid.modes.clear();
    // Write the outputs.
    io::WriteModelJson((out / "model.json").string(), model);
    io::WriteFrequencyResponse((out / "frf.csv").string(), frf);
    io::WriteBoundaryCsv((out / "boundary.csv").string(), rows);
    summary["log"] = source;
    summary["logs"] = f->logs;
    summary["estimate"] = ident::ToString(est.response.method);
    summary["whole_record"] = f->est.whole_record;
    summary["sample_rate_hz"] = frf.sample_rate_hz;
    summary["num_samples"] = est.total_samples;
    summary["fit"] = model.fit;
    summary["reference"] = have_ref ? (table1 ? "table1 (built in)" : f->reference) : "none";
    {  // The verdict first, above any Z-width computed from the model.
      nlohmann::ordered_json top = {{"fit_quality", fit::ToString(fr.quality)},
                                    {"fit_quality_reasons", nlohmann::ordered_json::parse(model.fit["quality_reasons"].dump())}};
      for (const auto& [k, v] : summary.items()) top[k] = nlohmann::ordered_json::parse(v.dump());
      io::WriteTextAtomically((out / "summary.json").string(), top.dump(2) + "\n");
    }
    t_total += timer.Lap("write outputs");
    std::fprintf(stderr, "  %-28s %9.3f ms\n", "total (figures excluded)", t_total);

    // Figure data and the gnuplot script.
    const fs::path fig = out / "figures";
    if (!f->no_figures) fs::create_directories(fig);
    if (!f->no_figures) {
      std::ostringstream b;
      b.precision(10);
      const bool joint = est.response.method == ident::CombinedMethod::kJoint;
      b << "# f_hz |H| phase_deg |G| phase_G_deg coherence" << (joint ? " coherence_ru coherence_ry" : "")
        << " used_by_fit\n";
      // The model's own sampled response (the loop's hand is not part of it).
      const stability::SampledPlant g = loop.hand.IsNone() ? sampled : stability::SampledPlant(model.plant, T);
      // Phases unwrapped along frequency (the model's continuously; the
      // measured one kept within half a turn of the model's).
      double pm_prev = 0.0;
      for (size_t k = 0; k < frf.f_hz.size(); ++k) {
        const double th = 2 * std::numbers::pi * frf.f_hz[k] * T;
        const auto gm = g.AtTheta(th);
        double pm = std::arg(gm) * 180 / std::numbers::pi;
        if (k > 0) pm += 360.0 * std::round((pm_prev - pm) / 360.0);
        pm_prev = pm;
        double ph = std::arg(frf.H[k]) * 180 / std::numbers::pi;
        ph += 360.0 * std::round((pm - ph) / 360.0);
        b << frf.f_hz[k] << " " << std::abs(frf.H[k]) << " " << ph << " " << std::abs(gm) << " " << pm << " "
          << frf.coherence[k];
        if (joint) b << " " << est.response.coherence_ru[k] << " " << est.response.coherence_ry[k];
        b << " " << (k < frf.used_by_fit.size() && frf.used_by_fit[k] ? 1 : 0) << "\n";
      }
      io::WriteTextAtomically((fig / "bode.dat").string(), b.str());
      // Curves: the model's are the boundary rows; reference and rigid-only
      // are computed here, for the figures alone.
      const stability::SampledPlant rigid_sampled(rigid, T);
      for (int which = 0; which < 3; ++which) {
        if (which == 1 && !have_ref) continue;
        std::ostringstream o;
        o.precision(10);
        for (size_t i = 0; i < f->delays.size(); ++i) {
          std::unique_ptr<stability::ZWidth> z;
          if (which == 2) z = std::make_unique<stability::ZWidth>(rigid_sampled, f->delays[i]);
          for (int k = 0; k < nB; ++k) {
            const auto c = which == 0 ? rows[i * nB + k].point : which == 1 ? ref_zs[i].At(bgrid[k]) : z->At(bgrid[k]);
            o << bgrid[k] << " " << c.K_cr << " " << c.f_cr_hz << " "
              << (which == 0 ? rows[i * nB + k].K_cr_std : std::numeric_limits<double>::quiet_NaN()) << "\n";
          }
          o << "\n\n";
        }
        io::WriteTextAtomically((fig / (which == 0 ? "kcr_model.dat" : which == 1 ? "kcr_reference.dat" : "kcr_rigid.dat")).string(), o.str());
      }
      // The stable set: one vertical segment per (B, interval), +inf drawn at
      // 1.2 x the largest finite K of the table.
      double k_clip = 0.0;
      for (const auto& r : rows) {
        for (const auto& iv : r.intervals) k_clip = std::max(k_clip, std::isfinite(iv.K_hi) ? iv.K_hi : iv.K_lo);
      }
      k_clip = k_clip > 0.0 ? 1.2 * k_clip : 1.0;
      {
        std::ostringstream o;
        o.precision(10);
        for (size_t i = 0; i < f->delays.size(); ++i) {
          o << "# delay " << f->delays[i] << ": B K_lo K_hi (K_hi = +inf drawn at " << k_clip << ")\n";
          bool any = false;
          for (int k = 0; k < nB; ++k) {
            for (const auto& iv : rows[i * nB + k].intervals) {
              o << bgrid[k] << " " << iv.K_lo << " " << std::min(iv.K_hi, k_clip) << "\n";
              any = true;
            }
          }
          if (!any) o << "nan nan nan\n";
          o << "\n\n";
        }
        io::WriteTextAtomically((fig / "region_model.dat").string(), o.str());
      }
      // The loop figure: the region without and with the report's velocity
      // filter, and the passivity boundary K_P(B) of each, on a grid to
      // 1.05 x the larger B_max.
      double k_clip_loop = k_clip;  // K_hi = +inf drawn at k_clip
      {
        stability::LoopOptions lf, lr;  // the loop's hand, with the report's filter / no filter
        lf.hand = lr.hand = loop.hand;
        stability::SetLowPassFilter(f->report_filter_hz, T, &lf);
        std::ostringstream o, q;
        o.precision(10);
        q.precision(10);
        for (size_t i = 0; i < f->delays.size(); ++i) {
          const stability::ZWidth zf(sampled, f->delays[i], lf), zr(sampled, f->delays[i], lr);
          const stability::Passivity pf(model.plant.b, T, zf.total_delay(), lf), pr(model.plant.b, T, zr.total_delay(), lr);
          // zr is the run's own loop when that has no filter: its summary is known.
          const double bm = std::max(loop.HasFilter() ? zr.Summarize().B_max : sums[i].B_max, zf.Summarize().B_max);
          const double top = std::isfinite(bm) && bm > 0 ? 1.05 * bm : bgrid.back();
          for (int k = 0; k < 300; ++k) {
            const double B = top * k / 299.0;
            for (int which = 0; which < 2; ++which) {
              for (const auto& iv : (which ? zf : zr).StableIntervals(B)) {
                o << B << " " << which << " " << iv.K_lo << " " << std::min(iv.K_hi, k_clip) << "\n";
                if (std::isfinite(iv.K_hi)) k_clip_loop = std::max(k_clip_loop, 1.05 * iv.K_hi);
              }
            }
            q << B << " " << pr.At(B).K_hi << " " << pf.At(B).K_hi << "\n";
          }
          o << "nan nan nan nan\n\n\n";
          q << "\n\n";
        }
        io::WriteTextAtomically((fig / "loop_region.dat").string(), o.str());
        io::WriteTextAtomically((fig / "loop_passive.dat").string(), q.str());
      }
      // Table II (the paper's relay points), drawn only beside Table I.
      if (table1) {
        std::ostringstream t2;
        for (const io::Table2Point& p : io::Table2Points()) {  // at the delays drawn
          if (std::find(f->delays.begin(), f->delays.end(), p.delay_samples) == f->delays.end()) continue;
          t2 << p.delay_samples << " " << p.B << " " << p.K_cr << " " << p.f_cr_hz << "\n";
        }
        io::WriteTextAtomically((fig / "table2.dat").string(), t2.str());
      }
      const FigureScriptOptions so{f->delays, est.response.method, joint, linear, have_ref, table1,
                                   k_clip, k_clip_loop, f->report_filter_hz};
      io::WriteTextAtomically((fig / "figures.gp").string(), FigureScript(so));
    }
    bool have_figures = false;
    if (!f->no_figures) {
      timer.Lap("figure data (reference, rigid)");
      // gnuplot started with an argument vector in the figures folder: no shell,
      // so no folder name is ever interpreted. 127: not installed.
      const int gnuplot = io::RunProgram({"gnuplot", "figures.gp"}, fig.string(), (fig / "gnuplot.log").string());
      have_figures = gnuplot == 0;
      if (gnuplot != 127) timer.Lap("figures (gnuplot)");
    }
    // The report.
    std::ostringstream h;
    h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>zwidth report</title>"
      << "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}pre{background:#f4f4f4;padding:8px}"
      << "img{max-width:100%}</style></head><body>\n<h1>zwidth report</h1>\n"
      << "<p><b>Fit quality: " << fit::ToString(fr.quality) << "</b>"
      << (fr.quality == fit::FitQuality::kGood ? "" : ": the Z-width below comes from a model that does not explain the log; do not rely on it") << "</p>\n<pre>" << Html(FitReport(fr)) << "</pre>\n"
      << "<p>Log <code>" << Html(source) << "</code>: " << est.total_samples << " samples at "
      << frf.sample_rate_hz << " Hz; Welch " << frf.num_averages << " averages of " << frf.window_length
      << " samples; " << Html(ident::ToString(est.response.method)) << "; " << frf.f_hz.size() << " bins from " << frf.f_hz.front() << " to " << frf.f_hz.back()
      << " Hz.</p>\n<h2>Fitted model (eq. 1)</h2>\n<pre>" << Html(ParameterTable(model, linear)) << "</pre>\n<p>"
      << Html(fr.BriefReport()) << ". Residual: exact ZOH response weighted by the Welch per-bin std. "
      << "Sections in canonical order (pole pairs by omega, zero pairs by v).</p>\n";
    for (const auto& w : fr.warnings) h << "<p><b>Warning:</b> " << Html(WithFlags(w)) << "</p>\n";
    if (have_ref) {
      h << "<h2>Comparison with the reference (" << Html(table1 ? "Table I, built in" : f->reference) << ")</h2>\n<pre>"
        << Html(cmp_text) << "</pre>\n";
    } else {
      h << "<p>No reference comparison (pass <code>--reference table1</code> or a model JSON to compare).</p>\n";
    }
    h << "<p>The paper's gain-margin reading of eq. (4) differs from the exact K_CR in " << disagree << " of "
      << rows.size() << " B values: mostly past B_max_from_zero, where margin() stays positive although K -> 0+ is unstable "
      << "(see boundary.csv, column margin_agrees).</p>\n";
    {
      std::ostringstream z;
      char line[256];
      std::snprintf(line, sizeof line, "%-6s %18s %18s %18s %12s %18s\n", "delay", "K_cr(B=0)", "B_t", "K_cr^max",
                    "B_max_0", "B_max");
      z << line;
      auto pm = [&](double v, double sd) {
        char b[64];
        if (std::isfinite(sd)) std::snprintf(b, sizeof b, "%.5g +- %.2g", v, sd);
        else std::snprintf(b, sizeof b, "%.5g", v);
        return std::string(b);
      };
      for (size_t i = 0; i < sums.size(); ++i) {
        const auto& s = sums[i];
        std::snprintf(line, sizeof line, "%-6d %18s %18s %18s %12.5g %18s\n", f->delays[i],
                      pm(s.K_cr_at_zero_B, stds[i].K_cr_at_zero_B).c_str(), pm(s.B_t, stds[i].B_t).c_str(),
                      pm(s.K_cr_max, stds[i].K_cr_max).c_str(), s.B_max_from_zero, pm(s.B_max, stds[i].B_max).c_str());
        z << line;
        for (const auto& band : s.reopened_bands) {
          std::snprintf(line, sizeof line, "       reopened band: B in (%.5g, %.5g), largest stable K %.5g\n",
                        band.B_lo, band.B_hi, band.K_max);
          z << line;
        }
      }
      h << "<h2>Z-width (eq. 2)</h2>\n<pre>" << Html(z.str()) << "</pre>\n<p>B_max_0: where the stable interval "
        << "from K = 0+ closes (the paper's B_max); B_max: the largest B at which some K &gt; 0 is stable. "
        << "+- one std by the delta method from the fit's parameter covariance"
        << (has_cov ? "" : " (not available: the fit has no covariance)") << ". boundary.csv lists every stable "
        << "K interval per B.</p>\n";
    }
    if (have_figures) {
      for (const char* name : {"bode", "coherence", "kcr", "region", "loop", "rigid"}) {
        h << "<p><img src='figures/" << name << ".svg' alt='" << name << "'></p>\n";
        if (std::string(name) == "loop") {
          h << "<p>Blue: the (B, K) the device renders stably with the raw backward difference; orange: with a "
            << f->report_filter_hz << " Hz first-order velocity low-pass. Lines: the passivity boundary K_P(B) "
            << "(Colgate and Schenkel, with the model's damping b = " << model.plant.b << "): below it the wall stays "
            << "passive, so it stays stable against any passive hand, which the stable region alone does not promise "
            << "(it assumes nobody holds the device). Passivity is bounded by the physical damping b (for the rigid "
            << "body without delay or filter: b > K T/2 + |B|), so on a lightly damped device its region hugs the "
            << "origin: rendering beyond it relies on the stable region and on the hand being no worse than assumed.</p>\n";
        }
      }
    } else if (f->no_figures) {
      h << "<p>No figures (<code>--no-figures</code>).</p>\n";
    } else {
      h << "<p>Figures need gnuplot (Debian package <code>gnuplot-nox</code>): install it and run "
        << "<code>cd figures && gnuplot figures.gp</code>, or rerun zwidth run.</p>\n";
    }
    h << "</body></html>\n";
    io::WriteTextAtomically((out / "report.html").string(), h.str());
    folder.Commit();
    std::printf("fit quality: %s\n%s\n%s", fit::ToString(fr.quality).c_str(), ParameterTable(model, linear).c_str(), cmp_text.c_str());
    std::fprintf(stderr, "%s", FitReport(fr).c_str());
    std::printf("\nboundary: %s (%d of %zu rows where margin() and the exact K_CR disagree)\nreport: %s\n",
                (final_out / "boundary.csv").c_str(), disagree, rows.size(), (final_out / "report.html").c_str());
  });
}

}  // namespace zwidth::app
