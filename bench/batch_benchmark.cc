// The per-unit cost of analysis::RunBatch (issue 28): 4 units, each a log of
// Table I simulated for 8 s (white torque, seeds 1..4, written as CSV),
// read, Welch-estimated (1024-sample windows), fitted (the order search, the
// friction looked at as `run` does: none found on these linear logs), and
// analysed as `run` does (delays 2 and 4, 20 B values), by run's pipeline
// (analysis::AnalyseUnit), on 1 and 2 threads. units_per_s beside
// error = the largest |K_CR^max(fit) / K_CR^max(Table I) - 1| at delay 2 over
// the units (what a fleet table is read for), and failed = rows not ok.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include <benchmark/benchmark.h>

#include "analysis/batch.h"
#include "analysis/compare.h"
#include "io/log.h"
#include "io/reference_models.h"
#include "model/simulate.h"

namespace zwidth {
namespace {

struct Fleet {
  std::filesystem::path dir;
  std::vector<io::BatchEntry> units;
  double kcr_max_true = 0.0;
  Fleet() {
    dir = std::filesystem::temp_directory_path() / ("zwidth_batch_bench_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const io::ModelFile table1 = io::Table1Model();
    for (int s = 1; s <= 4; ++s) {
      model::SimulateOptions o;
      o.seconds = 8.0;
      o.seed = static_cast<uint64_t>(s);
      const model::SimulatedLog log = model::SimulateLog(table1.plant, o);
      const std::string path = (dir / ("u" + std::to_string(s) + ".csv")).string();
      io::WriteLog(path, log.sample_rate_hz, log.torque, log.position);
      units.push_back({path, path, {}, "unit " + std::to_string(s)});
    }
    kcr_max_true = analysis::SummarizeDelays(table1, 1e-3, {2}).summaries[0].K_cr_max;
  }
  ~Fleet() { std::filesystem::remove_all(dir); }
};

// range(0): threads (units at once).
void BM_BatchPerUnit(benchmark::State& state) {
  static const Fleet fleet;
  analysis::BatchOptions o;
  o.run.delays = {2, 4};
  o.run.grid.b_points = 20;
  o.estimate_fit.estimate.welch.window_length = 1024;
  o.estimate_fit.fit.auto_modes = true;
  o.threads = static_cast<int>(state.range(0));
  analysis::BatchResult r;
  for (auto _ : state) r = analysis::RunBatch(fleet.units, o);
  double err = 0.0, failed = 0.0;
  for (const auto& row : r.table.rows) {
    if (row.at("status") != "ok") {
      ++failed;
      continue;
    }
    err = std::max(err, std::abs(std::stod(row.at("d2_K_cr_max")) / fleet.kcr_max_true - 1.0));
  }
  state.counters["error"] = err;
  state.counters["failed"] = failed;
  state.counters["units_per_s"] =
      benchmark::Counter(static_cast<double>(fleet.units.size()) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BatchPerUnit)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace zwidth
