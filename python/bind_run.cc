// zwidth.run: `zwidth run` from Python, by the same library function
// (report::RunToFolder) into the same folder (io::OutputFolder: a new or
// empty folder, or force; committed only when everything is written).
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "analysis/run_input.h"
#include "fit/fit.h"
#include "io/atomic_file.h"
#include "io/batch_table.h"
#include "io/model_json.h"
#include "io/option_names.h"
#include "io/provenance.h"
#include "io/reference_models.h"
#include "model/error.h"
#include "python/bind_common.h"
#include "report/run_report.h"

namespace zwidth::python {
namespace {

py::dict RunResult(const report::RunJobResult& r, const std::string& folder) {
  py::dict d;
  d["out_dir"] = folder;
  d["quality"] = fit::ToString(r.analysis.input.fit.quality);
  d["figures"] = r.report.figures == report::FiguresStatus::kDrawn            ? "drawn"
                 : r.report.figures == report::FiguresStatus::kGnuplotMissing ? "gnuplot missing"
                 : r.report.figures == report::FiguresStatus::kGnuplotFailed  ? "gnuplot failed"
                 : r.report.figures == report::FiguresStatus::kNotDrawn       ? "not drawn"
                                                                              : "none";
  d["fit_report"] = io::WithKeywords(r.fit_report);
  return d;
}

}  // namespace

void BindRun(py::module_& m) {
  const analysis::RunOptions d;
  m.def("_run",
        [](const py::object& logs, const py::object& out_path, const analysis::LogsEstimateOptions& estimate,
           const fit::FitOptions& fit, bool force, bool figures, bool png, const std::optional<std::string>& reference,
           const std::vector<int>& delays, const std::optional<std::string>& units, std::optional<double> velocity_filter_hz,
           std::optional<std::tuple<double, double, double>> hand, std::optional<double> b_step, int b_points,
           double report_filter_hz, const std::string& friction, bool table2, const std::string& command_line) {
          const std::string out_dir = PathFrom(out_path, "out_dir");
          report::RunJob job;
          job.input.logs = PathsFrom(logs);
          if (job.input.logs.empty()) throw InputError("logs: no log given: pass a log file's path (or several)");
          for (const std::string& p : job.input.logs) job.input.source += (job.input.source.empty() ? "" : " + ") + p;
          if (units) job.options.linear = io::ParseUnitsWord(*units, "units");  // None: the logs' headers
          job.options.delays = delays;
          job.options.figures = figures;
          job.options.report_filter_hz = Number(py::float_(report_filter_hz), "report_filter_hz");  // NaN refused, as the CLI
          if (b_step) job.options.grid.b_step = Number(py::float_(*b_step), "b_step");
          job.options.grid.b_points = b_points;
          if (table2) job.options.table2 = analysis::Table2Options{};  // `run --table2`'s defaults
          job.estimate_fit = {estimate, fit};
          job.estimate_fit.friction = analysis::FrictionModelNamed(friction);  // before anything is read, as the CLI
          if (units) job.estimate_fit.linear = job.options.linear;
          job.loop = [=](double period_s) { return LoopFrom(velocity_filter_hz, hand, period_s); };
          job.report = {.draw_figures = figures, .png = png, .fit_report = "", .command_line = command_line};
          std::string why;  // before anything is read or written, as the CLI
          if (!job.options.IsValid(&why)) throw InputError(io::WithKeywords(why));
          io::ForgetNotedInputs();  // each call is its own command (the provenance's inputs)
          io::SetInvocation(command_line);
          if (reference) {
            job.input.reference = io::ReadReferenceModel(CheckedPath(*reference, "reference"), "reference",
                                                         &job.input.reference_is_table1);
            job.input.reference_name = *reference;
          }
          // The run's files are `zwidth run`'s, byte for byte (advice in the CLI's
          // flags); what Python shows (warnings, the returned fit report) in its keywords.
          std::vector<std::string> warnings;
          analysis::RunMessages msg;
          msg.estimate = [&](const std::string& line) {
            if (line.rfind("warning: ", 0) == 0) warnings.push_back(io::WithKeywords(line.substr(9)));
          };
          msg.fit.words = io::WithFlags;
          msg.fit.warning = [&](const std::string& w) { warnings.push_back(io::WithKeywords(w)); };
          std::optional<report::RunJobResult> r;
          std::string final_path;
          {
            py::gil_scoped_release release;
            ScopedCLocale c;
            io::OutputFolder folder(out_dir, force);
            r.emplace(report::RunToFolder(std::move(job), folder, msg));
            folder.Commit();
            final_path = folder.path();
          }
          const py::object warn = py::module_::import("warnings").attr("warn");
          for (const std::string& w : warnings) warn(w, py::module_::import("builtins").attr("UserWarning"), 2);
          return RunResult(*r, final_path);
        },
        py::arg("logs"), py::arg("out_dir"), py::arg("estimate"), py::arg("fit"), py::arg("force") = false,
        py::arg("figures") = d.figures, py::arg("png") = false, py::arg("reference") = py::none(),
        py::arg("delays") = d.delays, py::arg("units") = py::none(), py::arg("velocity_filter_hz") = py::none(),
        py::arg("hand") = py::none(), py::arg("b_step") = py::none(), py::arg("b_points") = d.grid.b_points,
        py::arg("report_filter_hz") = d.report_filter_hz, py::arg("friction") = "auto", py::arg("table2") = false,
        py::arg("command_line") = "",
        "zwidth.run's core: the options made by _estimate_logs_options and _fit_options.", kCLocale);
  // zwidth.batch's tables (python/zwidth/_batch.py works on their CSV text): io::ReadBatchTable
  // and io::WriteBatchTable, so that a table at an .h5 path is the command's HDF5 table.
  m.def("_read_batch_table",
        [](const std::string& path) {
          io::BatchTable t;
          {
            py::gil_scoped_release release;
            t = io::ReadBatchTable(path);
          }
          return io::FormatBatchCsv(t);
        },
        py::arg("path"), "The batch table at path (CSV or HDF5) as CSV text.", kCLocale);
  m.def("_write_batch_table",
        [](const std::string& path, const std::string& csv_text) {
          py::gil_scoped_release release;
          io::WriteBatchTable(path, io::ParseBatchCsv(csv_text, "the rows of zwidth.batch"));
        },
        py::arg("path"), py::arg("csv_text"),
        "Writes a batch table's CSV text to path atomically: HDF5 for .h5/.hdf5/.he5, else CSV.", kCLocale);
}

}  // namespace zwidth::python
