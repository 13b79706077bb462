#include "report/run_report.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <optional>

#include <nlohmann/json.hpp>

#include "analysis/laps.h"
#include "io/frf_file.h"
#include "io/printable.h"
#include "io/provenance.h"
#include "io/stability_files.h"
#include "model/c_locale.h"
#include "model/error.h"
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
    io::AddDelays(&e, st.delays[i], in.model.plant.delay_samples);
    if (!st.friction_amplitudes.empty()) {
      e["friction"] = analysis::FrictionSummaryJson(st.friction_amplitudes, st.delays[i], st.friction,
                                                    st.friction_options);
    }
    summary["boundary"].push_back(e);
  }
  summary["B_max_meaning"] = "B_max: the largest B at which some K > 0 is stable (reopened bands included); "
                             "B_max_from_zero: the B where the interval from K = 0+ closes (the paper's B_max)";
  summary["margin_disagreements"] = st.margin_disagreements;
  if (a.comparison) summary["comparison"] = a.comparison->json;
  if (a.table2) summary["table2"] = analysis::Table2Json(*a.table2);
  // File names as valid UTF-8 (a Latin-1 name made the JSON writer throw after all the work).
  summary["log"] = io::Utf8ForJson(in.source);
  summary["logs"] = nlohmann::json::array();
  for (const std::string& log : in.logs) summary["logs"].push_back(io::Utf8ForJson(log));
  summary["estimate"] = ident::ToString(in.response.method);
  // The estimator that made the response (ident::FrequencyResponse::estimator), as the model file's fit says.
  summary["estimator"] = in.response.frf.estimator.empty() ? std::string("unknown") : in.response.frf.estimator;
  summary["whole_record"] = in.whole_record;
  summary["sample_rate_hz"] = in.response.frf.sample_rate_hz;
  summary["num_samples"] = in.total_samples;
  summary["fit"] = in.model.fit;
  summary["reference"] = in.reference ? (in.reference_is_table1 ? "table1 (built in)" : io::Utf8ForJson(in.reference_name)) : "none";
  nlohmann::ordered_json top = {{"fit_quality", fit::ToString(in.fit.quality)},
                                {"fit_quality_reasons", nlohmann::ordered_json::parse(in.model.fit.value("quality_reasons", nlohmann::json::array()).dump())}};
  for (const auto& [k, v] : summary.items()) top[k] = nlohmann::ordered_json::parse(v.dump());
  top["provenance"] = nlohmann::ordered_json::parse(io::ProvenanceJson().dump());
  return top.dump(2) + "\n";
}

void WriteDataFiles(const analysis::RunAnalysis& a, const fs::path& out) {
  io::WriteModelJson((out / "model.json").string(), a.input.model);
  io::WriteFrequencyResponse((out / "frf.csv").string(), a.input.response.frf);
  io::WriteBoundaryCsv((out / "boundary.csv").string(), a.stability.rows);
  io::WriteTextAtomically((out / "summary.json").string(), SummaryJson(a));
}

// The SVGs gnuplot drew, by name, for report.html to inline.
std::map<std::string, std::string> DrawnSvgs(const fs::path& fig) {
  std::map<std::string, std::string> svgs;
  for (const char* name : {"bode", "coherence", "kcr", "region", "loop", "rigid"}) {
    std::ifstream in(fig / (std::string(name) + ".svg"), std::ios::binary);
    if (!in) continue;
    std::ostringstream text;
    text << in.rdbuf();
    svgs[name] = text.str();
  }
  return svgs;
}

FiguresStatus StatusOf(int gnuplot_exit) {
  return gnuplot_exit == 0     ? FiguresStatus::kDrawn
         : gnuplot_exit == 127 ? FiguresStatus::kGnuplotMissing
                               : FiguresStatus::kGnuplotFailed;
}

}  // namespace

RunReport WriteRunReport(const analysis::RunAnalysis& a, const io::OutputFolder& folder,
                         const RunReportOptions& options) {
  const ScopedCLocale c_locale;  // the numbers of every file below, whatever the caller's locale
  const fs::path out(folder.temp_path());
  const fs::path fig = out / "figures";
  RunReport r;
  Laps laps;
  // gnuplot starts first: it loads while the files are written.
  std::optional<GnuplotProcess> gnuplot;
  if (a.figures && options.draw_figures) {
    fs::create_directories(fig);
    gnuplot.emplace(fig);
  }
  WriteDataFiles(a, out);
  r.stages.push_back({"write outputs", laps.Lap()});
  if (a.figures) {
    const std::string script = WriteFigureFiles(a, fig, options.png);
    r.stages.push_back({"figure files", laps.Lap()});
    r.figures = FiguresStatus::kNotDrawn;
    if (gnuplot) {
      r.figures = StatusOf(gnuplot->Run(script));
      if (r.figures != FiguresStatus::kGnuplotMissing) r.stages.push_back({"figures (gnuplot)", laps.Lap()});
    }
  }
  const std::map<std::string, std::string> svgs =
      r.figures == FiguresStatus::kDrawn ? DrawnSvgs(fig) : std::map<std::string, std::string>{};
  io::WriteTextAtomically((out / "report.html").string(), RunHtml(a, svgs, options.fit_report, options.command_line));
  return r;
}

RunJobResult RunToFolder(RunJob job, const io::OutputFolder& folder, const analysis::RunMessages& messages) {
  double ms = 0.0;
  RunJobResult r{analysis::EstimateFitAndAnalyse(std::move(job.input), job.estimate_fit, std::move(job.options), job.loop,
                                                 messages, &ms),
                 {}, {}, ms};
  r.fit_report = job.report.fit_report.empty() ? messages.fit.Words(analysis::FitReport(r.analysis.input.fit))
                                               : job.report.fit_report;
  job.report.fit_report = r.fit_report;
  r.report = WriteRunReport(r.analysis, folder, job.report);
  return r;
}

}  // namespace zwidth::report
