// zwidth run: estimate -> fit -> compare -> boundary -> report, the job a user
// runs on a new device log. Figures are drawn by gnuplot when it is installed.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <fstream>
#include <numbers>
#include <sstream>

#include "apps/common.h"
#include "apps/fit_support.h"
#include "io/atomic_file.h"
#include "io/frf_file.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "model/state_space.h"
#include "stability/zwidth.h"

namespace zwidth::app {
namespace fs = std::filesystem;
namespace {

// Table II of the paper (datasets/phantom/table2.csv), used for Fig. 10.
std::vector<std::array<double, 4>> ReadTable2(const std::string& path) {
  std::vector<std::array<double, 4>> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::array<double, 4> r{};
    // Rows with a note are the two misprinted ones (see the CSV): not plotted.
    const bool flagged = line.find_first_not_of(", \r", line.find(',', line.find(',', line.find(',', line.find(',') + 1) + 1) + 1) + 1) != std::string::npos;
    if (!flagged && std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &r[0], &r[1], &r[2], &r[3]) == 4) rows.push_back(r);
  }
  return rows;
}

std::string Html(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;"; else if (c == '>') o += "&gt;"; else if (c == '&') o += "&amp;"; else o += c;
  }
  return o;
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  struct RunFlags {
    std::string log, outdir, reference;
    std::vector<int> delays = {2, 4, 8};
    EstimateFlags est;
    FitFlags fit;
    double b_step = 0.0005;
  };
  auto f = std::make_shared<RunFlags>();
  CLI::App* cmd = app.add_subcommand("run", "estimate, fit, compare, Z-width boundary and an HTML report");
  cmd->add_option("log", f->log, "log file (.h5 or .csv)")->required();
  cmd->add_option("-o,--output", f->outdir, "output folder (created if its parent exists)")->required();
  cmd->add_option("--reference", f->reference, "reference model (default datasets/phantom/table1.json)");
  cmd->add_option("--delays", f->delays, "loop delays [samples]")->delimiter(',')->capture_default_str();
  f->fit.modes = "auto";  // run chooses the order unless told
  AddFitFlags(cmd, &f->fit);
  cmd->add_option("--b-step", f->b_step, "B step of the boundary [N m s/rad]")->capture_default_str();
  AddEstimateFlags(cmd, &f->est);
  cmd->callback([f] {
    f->fit.Resolve(f->est.welch.fmin_hz, f->est.welch.fmax_hz);
    for (int d : f->delays) if (d < 0) throw InputError("--delays must be >= 0");
    if (!(f->b_step > 0)) throw InputError("--b-step must be > 0");
    const fs::path out(f->outdir);
    if (!fs::is_directory(out)) {
      io::CheckOutputFolder(f->outdir);  // its parent must exist
      std::error_code ec;
      fs::create_directory(out, ec);
      if (ec) throw InputError("cannot create output folder '" + f->outdir + "': " + ec.message());
    }
    const std::string ref_path = f->reference.empty() ? DefaultReferencePath() : f->reference;
    const io::ModelFile ref = io::ReadModelJson(ref_path);
    std::fprintf(stderr, "zwidth run %s -> %s\n", f->log.c_str(), f->outdir.c_str());
    StageTimer timer;
    io::LogInfo info;
    ident::FrequencyResponse frf = EstimateFromLog(f->log, f->est, &info);
    double t_total = timer.Lap("estimate (read + Welch)");
    fit::FitResult fr;
    const io::ModelFile model = FitToModelFile(frf, f->fit.o, f->log, &fr);
    frf.used_by_fit = fr.band.used;
    t_total += timer.Lap("fit");
    const double T = 1.0 / frf.sample_rate_hz;
    // The model's Z-width per delay, computed once for the summary, the
    // comparison, the boundary rows and the figures.
    std::vector<stability::ZWidth> zs;
    std::vector<stability::DelaySummary> sums;
    nlohmann::json summary;
    summary["boundary"] = nlohmann::json::array();
    double b_max = 0.0;
    for (int d : f->delays) {
      zs.emplace_back(model.plant, T, d);
      sums.push_back(zs.back().Summarize());
      if (std::isfinite(sums.back().B_max)) b_max = std::max(b_max, sums.back().B_max);
      nlohmann::json e = io::SummaryToJson(sums.back());
      e["delay_samples"] = d;
      summary["boundary"].push_back(e);
    }
    if (b_max <= 0) b_max = 0.4;
    const int nB = static_cast<int>(std::floor(1.02 * b_max / f->b_step)) + 1;
    std::vector<io::BoundaryRow> rows;
    int disagree = 0;
    for (size_t i = 0; i < zs.size(); ++i) {
      for (int k = 0; k < nB; ++k) {
        rows.push_back({f->delays[i], zs[i].At(k * f->b_step)});
        if (!rows.back().point.AgreesWithMargin()) ++disagree;
      }
    }
    summary["margin_disagreements"] = disagree;
    t_total += timer.Lap("boundary");
    std::string cmp_text;
    summary["comparison"] = CompareModels(model, ref, f->delays, T, &cmp_text, &sums);
    t_total += timer.Lap("compare (reference Z-width)");
    Plant rigid = model.plant;
    rigid.modes.clear();
    // Write the outputs.
    io::WriteModelJson((out / "model.json").string(), model);
    io::WriteFrequencyResponse((out / "frf.csv").string(), frf);
    io::WriteBoundaryCsv((out / "boundary.csv").string(), rows);
    summary["log"] = f->log;
    summary["sample_rate_hz"] = frf.sample_rate_hz;
    summary["num_samples"] = info.num_samples;
    summary["fit"] = model.fit;
    summary["reference"] = ref_path;
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
    fs::create_directories(fig);
    {
      std::ostringstream b;
      b.precision(10);
      b << "# f_hz |H| phase_deg |G| phase_G_deg coherence\n";
      const DiscreteResponse g(DiscretizeZoh(model.plant, T));
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
          << frf.coherence[k] << "\n";
      }
      io::WriteTextAtomically((fig / "bode.dat").string(), b.str());
      // Curves: the model's are the boundary rows; reference and rigid-only
      // are computed here, for the figures alone.
      for (int which = 0; which < 3; ++which) {
        std::ostringstream o;
        o.precision(10);
        for (size_t i = 0; i < f->delays.size(); ++i) {
          const Plant& p = which == 1 ? ref.plant : rigid;
          std::unique_ptr<stability::ZWidth> z;
          if (which != 0) z = std::make_unique<stability::ZWidth>(p, T, f->delays[i]);
          for (int k = 0; k < nB; ++k) {
            const auto c = which == 0 ? rows[i * nB + k].point : z->At(k * f->b_step);
            o << k * f->b_step << " " << c.K_cr << " " << c.f_cr_hz << "\n";
          }
          o << "\n\n";
        }
        io::WriteTextAtomically((fig / (which == 0 ? "kcr_model.dat" : which == 1 ? "kcr_reference.dat" : "kcr_rigid.dat")).string(), o.str());
      }
      std::ostringstream t2;
      const bool table1 = fs::equivalent(ref_path, DefaultReferencePath());
      if (table1) {
        for (const auto& r : ReadTable2(std::string(ZWIDTH_SOURCE_DIR) + "/datasets/phantom/table2.csv")) {
          t2 << r[0] << " " << r[1] << " " << r[2] << " " << r[3] << "\n";
        }
      }
      io::WriteTextAtomically((fig / "table2.dat").string(), t2.str());
      std::ostringstream gp;
      gp << "set datafile missing 'nan'\nset grid\nset key outside right\n"
         << "set linetype 1 lc rgb '#1f77b4' lw 2\nset linetype 2 lc rgb '#d62728' lw 2\n"
         << "set linetype 3 lc rgb '#2ca02c' lw 2\nset linetype 4 lc rgb '#9467bd' lw 2\n"
         << "set linetype 5 lc rgb '#ff7f0e' lw 2\nset linetype 6 lc rgb '#8c564b' lw 2\n";
      std::string dl;
      for (size_t i = 0; i < f->delays.size(); ++i) dl += (i ? " " : "") + std::to_string(f->delays[i]);
      gp << "delays = '" << dl << "'\n";
      for (const char* term : {"svg size 900,640 font 'sans,12'", "pngcairo size 900,640 font 'sans,10'"}) {
        const std::string ext = std::string(term).rfind("svg", 0) == 0 ? "svg" : "png";
        gp << "set terminal " << term << "\n";
        gp << "set output 'bode." << ext << "'\nset multiplot layout 2,1 title 'Bode diagram: measured (Welch H1) and fitted model (exact ZOH) - Fig. 3'\n"
           << "set logscale x\nset logscale y\nset format y '10^{%L}'\nset ylabel 'magnitude [rad/(N m)]'\nunset xlabel\n"
           << "plot 'bode.dat' u 1:2 w l lc rgb '#1f77b4' t 'measured', '' u 1:4 w l lw 2 lc rgb 'black' t 'fitted model'\n"
           << "unset logscale y\nset format y '%g'\nset ylabel 'phase [deg]'\nset xlabel 'frequency [Hz]'\n"
           << "plot 'bode.dat' u 1:3 w l lc rgb '#1f77b4' t 'measured', '' u 1:5 w l lw 2 lc rgb 'black' t 'fitted model'\nunset multiplot\n";
        gp << "set output 'coherence." << ext << "'\nset title 'Magnitude-squared coherence'\nset xlabel 'frequency [Hz]'\nset ylabel 'coherence [-]'\nset yrange [0:1.05]\n"
           << "plot 'bode.dat' u 1:6 w l lc rgb '#1f77b4' t 'coherence'\nset yrange [*:*]\nunset logscale x\nunset title\n";
        gp << "set output 'kcr." << ext << "'\nset multiplot layout 2,1 title 'Critical stiffness and ultimate frequency vs damping - Fig. 6 / Fig. 10'\n"
           << "set xlabel 'B [N m s/rad]'\nset ylabel 'K_{CR} [N m/rad]'\n"
           << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:2 w l lt i t 'model, d='.word(delays,i), "
           << "for [i=1:words(delays)] 'kcr_reference.dat' index i-1 u 1:2 w l lt i dt 2 lw 1 t 'reference, d='.word(delays,i)"
           << (table1 ? ", 'table2.dat' u 2:3 w p pt 7 ps 0.8 lc rgb 'red' t 'Table II (relay)'" : "") << "\n"
           << "set logscale y\nset ylabel 'f_{CR} [Hz]'\n"
           << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:3 w l lt i t 'model, d='.word(delays,i)"
           << (table1 ? ", 'table2.dat' u 2:4 w p pt 7 ps 0.8 lc rgb 'red' t 'Table II (relay)'" : "") << "\nunset logscale y\nunset multiplot\n";
        gp << "set output 'rigid." << ext << "'\nset title 'With the vibration modes and without (rigid body only) - Fig. 7'\n"
           << "set xlabel 'B [N m s/rad]'\nset ylabel 'K_{CR} [N m/rad]'\n"
           << "plot for [i=1:words(delays)] 'kcr_model.dat' index i-1 u 1:2 w l lt i t 'with modes, d='.word(delays,i), "
           << "for [i=1:words(delays)] 'kcr_rigid.dat' index i-1 u 1:2 w l lt i dt 2 t 'rigid only, d='.word(delays,i)\nunset title\n";
      }
      io::WriteTextAtomically((fig / "figures.gp").string(), gp.str());
    }
    timer.Lap("figure data (reference, rigid)");
    bool have_figures = false;
    if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
      const std::string cmdline = "cd '" + fig.string() + "' && gnuplot figures.gp 2>gnuplot.log";
      have_figures = std::system(cmdline.c_str()) == 0;
      timer.Lap("figures (gnuplot)");
    }
    // The report.
    std::ostringstream h;
    h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>zwidth report</title>"
      << "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}pre{background:#f4f4f4;padding:8px}"
      << "img{max-width:100%}</style></head><body>\n<h1>zwidth report</h1>\n"
      << "<p><b>Fit quality: " << fit::ToString(fr.quality) << "</b>"
      << (fr.quality == fit::FitQuality::kGood ? "" : ": the Z-width below comes from a model that does not explain the log; do not rely on it") << "</p>\n<pre>" << Html(FitReport(fr)) << "</pre>\n"
      << "<p>Log <code>" << Html(f->log) << "</code>: " << info.num_samples << " samples at "
      << frf.sample_rate_hz << " Hz; Welch " << frf.num_averages << " averages of " << frf.window_length
      << " samples; " << frf.f_hz.size() << " bins from " << frf.f_hz.front() << " to " << frf.f_hz.back()
      << " Hz.</p>\n<h2>Fitted model (eq. 1)</h2>\n<pre>" << Html(ParameterTable(model)) << "</pre>\n<p>"
      << Html(fr.BriefReport()) << ". Residual: exact ZOH response weighted by the Welch per-bin std. "
      << "Sections in canonical order (pole pairs by omega, zero pairs by v).</p>\n";
    for (const auto& w : fr.warnings) h << "<p><b>Warning:</b> " << Html(w) << "</p>\n";
    h << "<h2>Comparison with the reference (" << Html(ref_path) << ")</h2>\n<pre>" << Html(cmp_text) << "</pre>\n";
    h << "<p>The paper's gain-margin reading of eq. (4) differs from the exact K_CR in " << disagree << " of "
      << rows.size() << " boundary rows: mostly past B_max, where margin() stays positive although no K is stable "
      << "(see boundary.csv, column margin_agrees).</p>\n";
    if (have_figures) {
      for (const char* name : {"bode", "coherence", "kcr", "rigid"}) {
        h << "<p><img src='figures/" << name << ".svg' alt='" << name << "'></p>\n";
      }
    } else {
      h << "<p>Figures need gnuplot (Debian package <code>gnuplot-nox</code>): install it and run "
        << "<code>cd figures && gnuplot figures.gp</code>, or rerun zwidth run.</p>\n";
    }
    h << "</body></html>\n";
    io::WriteTextAtomically((out / "report.html").string(), h.str());
    std::printf("fit quality: %s\n%s\n%s", fit::ToString(fr.quality).c_str(), ParameterTable(model).c_str(), cmp_text.c_str());
    std::fprintf(stderr, "%s", FitReport(fr).c_str());
    std::printf("\nboundary: %s (%d of %zu rows where margin() and the exact K_CR disagree)\nreport: %s\n",
                (out / "boundary.csv").c_str(), disagree, rows.size(), (out / "report.html").c_str());
  });
}

}  // namespace zwidth::app
