// zwidth.batch's core (python/zwidth/_batch.py): `zwidth batch`'s request
// parsed by the command's own declarations (flags::ParseBatchRequest, below
// apps: the same flags, checks and options key), each unit computed in this
// process by the batch engine (analysis::RunBatch on that one unit: run's
// pipeline, its row, its resume by input hash, its errors as a row) with the
// GIL released, so Python threads or a dask worker's threads compute units
// side by side; the rows finished so far saved as the command saves them
// (analysis::BatchTableSaver); then the batch's end as the command's
// (flags::FinishBatch: every unit resumed from the rows, the outlier columns,
// the table written by io::WriteBatchTable). The request records the Python
// call that made it (the unit folders' and the fleet report's command).
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/batch.h"
#include "flags/batch_request.h"
#include "io/provenance.h"
#include "io/atomic_file.h"
#include "io/batch_table.h"
#include "io/option_names.h"
#include "model/error.h"
#include "model/parallel.h"
#include "python/bind_common.h"

namespace zwidth::python {
namespace {

using Cells = std::map<std::string, std::string>;

// The request of (batch id, arguments), parsed once per process: a dask worker
// computes many units of one batch; a new zwidth.batch call has a new id, so a
// changed design or manifest is read again.
std::shared_ptr<const flags::BatchRequest> Request(const std::string& batch_id, const std::vector<std::string>& args,
                                                   const std::string& call) {
  static std::mutex mu;
  static std::vector<std::pair<std::pair<std::string, std::vector<std::string>>, std::shared_ptr<const flags::BatchRequest>>> cache;
  const auto key = std::make_pair(batch_id, args);
  {
    std::lock_guard<std::mutex> lock(mu);
    for (const auto& [k, r] : cache) {
      if (k == key) return r;
    }
  }
  std::shared_ptr<const flags::BatchRequest> r = flags::ParseBatchRequest(args, call);
  std::lock_guard<std::mutex> lock(mu);
  if (cache.size() >= 4) cache.erase(cache.begin());
  cache.emplace_back(key, r);
  return r;
}

// A row as a dict of its text cells, in the table's column order (a column it lacks is empty in the table).
py::dict RowDict(const Cells& row) {
  py::dict d;
  for (const std::string& c : analysis::BatchColumns({row})) {
    if (auto it = row.find(c); it != row.end()) d[py::str(c)] = it->second;
  }
  return d;
}

// The saver of each batch running here (by its id): the rows finished so far
// written as `zwidth batch` writes them while it runs.
std::mutex g_savers_mu;
std::map<std::string, std::shared_ptr<analysis::BatchTableSaver>> g_savers;

Cells CellsFrom(const py::dict& d) {
  Cells row;
  for (const auto& [k, v] : d) row[py::cast<std::string>(k)] = py::cast<std::string>(v);
  return row;
}

}  // namespace

void BindBatch(py::module_& m) {
  m.def("_batch_flag",
        [](const std::string& keyword) {
          // The option table's flag for a keyword (io/option_names.cc), else the keyword with dashes.
          for (const io::OptionName& n : io::OptionNames()) {
            if (keyword == n.keyword && *n.flag) return std::string(n.flag);
          }
          std::string flag = "--" + keyword;
          for (char& c : flag) c = c == '_' ? '-' : c;
          return flag;
        },
        py::arg("keyword"), "The `zwidth batch` flag of a keyword.", kCLocale);
  m.def("_batch_units",
        [](const std::vector<std::string>& args, const std::string& batch_id, const std::string& call) {
          io::ForgetNotedInputs();  // each call is its own command (the provenance's inputs)
          io::SetInvocation(call);  // the provenance of the unit folders' JSON files
          std::shared_ptr<const flags::BatchRequest> r;
          std::vector<std::optional<Cells>> resumed;
          {
            py::gil_scoped_release release;
            ScopedCLocale c;
            r = Request(batch_id, args, call);
            const io::BatchTable previous = flags::PreviousBatchTable(*r);
            std::map<std::string, const Cells*> by_serial;
            for (const Cells& row : previous.rows) {
              if (auto it = row.find("serial"); it != row.end()) by_serial[it->second] = &row;
            }
            // The engine's rule: a previous row is taken when its input_hash is the unit's now.
            for (const io::BatchEntry& e : r->units) {
              auto it = by_serial.find(e.serial);
              std::optional<Cells> row;
              if (it != by_serial.end()) {
                const std::string hash = analysis::UnitInputHash(e, r->options);
                auto h = it->second->find("input_hash");
                if (!hash.empty() && h != it->second->end() && h->second == hash) row = *it->second;
              }
              resumed.push_back(std::move(row));
            }
            std::lock_guard<std::mutex> lock(g_savers_mu);
            if (g_savers.size() >= 16) g_savers.erase(g_savers.begin());
            g_savers[batch_id] = std::make_shared<analysis::BatchTableSaver>(r->table);
          }
          py::list units;
          for (size_t i = 0; i < r->units.size(); ++i) {
            units.append(py::make_tuple(r->units[i].serial, resumed[i] ? py::object(RowDict(*resumed[i])) : py::object(py::none())));
          }
          return units;
        },
        py::arg("args"), py::arg("batch_id"), py::arg("call") = "",
        "The units of `zwidth batch ARGS`: (serial, its row of the table at -o when its inputs hash the same, "
        "else None: to compute); InputError for a bad request, before any unit is computed.",
        kCLocale);
  m.def("_batch_unit",
        [](const std::vector<std::string>& args, const std::string& batch_id, size_t index, const std::string& serial,
           bool serial_thread, const std::string& call) {
          io::ForgetNotedInputs();  // each call is its own command (the provenance's inputs)
          io::SetInvocation(call);  // a dask worker's too
          Cells row;
          {
            py::gil_scoped_release release;
            ScopedCLocale c;
            std::shared_ptr<const flags::BatchRequest> r = Request(batch_id, args, call);
            if (index >= r->units.size() || r->units[index].serial != serial) {
              throw InputError("batch: unit " + std::to_string(index) + " is not '" + serial +
                               "' here: the units (a glob, a manifest) differ between the caller and this process");
            }
            analysis::BatchOptions o = r->options;
            o.threads = 1;
            // One unit per Python thread: its own work on its thread alone, as the command's --jobs.
            std::optional<ScopedSerialThread> alone;
            if (serial_thread) alone.emplace();
            row = analysis::RunBatch({r->units[index]}, o, r->unit_options, r->unit_done).table.rows.at(0);
          }
          return RowDict(row);
        },
        py::arg("args"), py::arg("batch_id"), py::arg("index"), py::arg("serial"), py::arg("serial_thread") = true,
        py::arg("call") = "",
        "Unit `index` of `zwidth batch ARGS` computed here, its own work on this thread alone when serial_thread: "
        "its row of text cells (an error as a row).",
        kCLocale);
  m.def("_batch_finish",
        [](const std::vector<std::string>& args, const std::string& batch_id, const std::vector<py::dict>& rows,
           const std::string& call) {
          io::BatchTable done;
          for (const py::dict& d : rows) done.rows.push_back(CellsFrom(d));
          py::gil_scoped_release release;
          ScopedCLocale c;
          std::shared_ptr<const flags::BatchRequest> r = Request(batch_id, args, call);
          analysis::BatchOptions o = r->options;
          done.columns = analysis::BatchColumns(done.rows);
          o.previous = std::move(done);
          // Every unit resumed from its row (the same input hash), as `zwidth batch` run again.
          const analysis::BatchResult result = analysis::RunBatch(r->units, o, r->unit_options, r->unit_done);
          {
            std::lock_guard<std::mutex> lock(g_savers_mu);
            g_savers.erase(batch_id);
          }
          return io::FormatBatchCsv(flags::FinishBatch(*r, result));
        },
        py::arg("args"), py::arg("batch_id"), py::arg("rows"), py::arg("call") = "",
        "The end of `zwidth batch ARGS` from the units' rows: the table written at -o (and --population, "
        "--fleet-report); returns its CSV text.",
        kCLocale);
  m.def("_batch_progress",
        [](const std::string& batch_id, const std::vector<std::optional<py::dict>>& rows, bool now) {
          std::vector<std::optional<Cells>> done;
          size_t finished = 0;
          for (const std::optional<py::dict>& d : rows) {
            done.push_back(d ? std::optional<Cells>(CellsFrom(*d)) : std::nullopt);
            finished += d ? 1 : 0;
          }
          std::shared_ptr<analysis::BatchTableSaver> saver;
          {
            std::lock_guard<std::mutex> lock(g_savers_mu);
            if (auto it = g_savers.find(batch_id); it != g_savers.end()) saver = it->second;
          }
          if (!saver) return;
          py::gil_scoped_release release;
          ScopedCLocale c;
          if (now) saver->Save(done);
          else (*saver)({.total = done.size(), .done = finished}, done);
        },
        py::arg("batch_id"), py::arg("rows"), py::arg("now") = false,
        "The rows finished so far (None: not yet) saved at the batch's -o as `zwidth batch` saves them while "
        "it runs (every 2 s while units are left; at once with now: an interrupt), so a killed batch resumes.",
        kCLocale);
}

}  // namespace zwidth::python
