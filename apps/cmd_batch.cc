// zwidth batch: `run`'s estimate, fit and Z-width for many units (a log
// each), into one table (analysis/batch.h). This file only wires: the
// request (flags/batch_request.h: the declarations, the units, each unit's
// log flags, the previous table and the batch's end, shared with Python's
// zwidth.batch), the progress on a terminal, the table saved now and then
// (analysis::BatchTableSaver). Each unit is computed by run's pipeline
// (analysis::AnalyseUnit).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/batch.h"
#include "apps/common.h"
#include "flags/batch_request.h"
#include "io/printable.h"
#include "model/parallel.h"

namespace zwidth::app {
namespace {

std::string Clock(double s) {
  if (!std::isfinite(s)) return "?";
  const long t = std::lround(s);
  char b[32];
  std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
  return b;
}

void Batch(BatchFlags& b, const CLI::App* cmd) {
  const std::shared_ptr<BatchRequest> req = PrepareBatch(b, cmd, CommandLine());
  analysis::BatchOptions& o = req->options;
  const int cores = NumThreads();
  if (b.jobs > cores) std::fprintf(stderr, "note: --jobs %d: %d core(s) available, %d units at once\n", b.jobs, cores, o.threads);
  // Each unit's own work on its thread alone, the fit's plugin included (it
  // reads ZWIDTH_NUM_THREADS on each call).
  if (o.threads > 1) setenv("ZWIDTH_NUM_THREADS", "1", 1);
  o.previous = PreviousBatchTable(*req);

  const bool terminal = isatty(STDERR_FILENO) == 1;
  analysis::BatchTableSaver save(b.table);  // every 2 s: an interrupted batch resumes from there
  auto on_progress = [&](const analysis::BatchProgress& p, const std::vector<std::optional<std::map<std::string, std::string>>>& rows) {
    if (terminal) {
      std::fprintf(stderr, "\r\033[Kbatch: %zu/%zu units (%zu failed, %zu resumed), %.2f units/s, %s left", p.done, p.total,
                   p.failed, p.resumed, p.rate_per_s(), Clock(p.seconds_left()).c_str());
    }
    save(p, rows);
  };
  const auto start = std::chrono::steady_clock::now();
  const analysis::BatchResult r = analysis::RunBatch(req->units, o, req->unit_options, req->unit_done, on_progress);
  FinishBatch(*req, r);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (terminal) std::fprintf(stderr, "\n");
  std::fprintf(stderr, "batch: %zu units, %zu ok, %zu failed, %zu resumed, %zu computed in %.3f s (%.3g units/s on %d thread%s) -> %s\n",
               r.progress.total, r.progress.total - r.progress.failed, r.progress.failed, r.progress.resumed,
               r.progress.computed, s, r.progress.computed / s, o.threads, o.threads > 1 ? "s" : "",
               io::Printable(b.table).c_str());
  if (r.progress.failed > 0) throw ExitStatus{4};
}

}  // namespace

void AddBatchCommand(CLI::App& app) {
  auto b = std::make_shared<BatchFlags>();
  CLI::App* cmd = DeclareBatch(app, b);
  cmd->callback([b, cmd] { Batch(*b, cmd); });
}

}  // namespace zwidth::app
