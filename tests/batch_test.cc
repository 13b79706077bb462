// analysis/batch.h RunBatch: a unit's error is its row and the others go on,
// rows in the units' order whatever the threads, resume by the input hash
// (the caller's estimate and fit not called again), a changed log or option
// (the friction model among them) computed again, a cancel stops the batch. The estimate and fit here hand
// Table I as the fitted model (no log is fitted: the engine is under test).
#include <atomic>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "analysis/batch.h"
#include "io/reference_models.h"
#include "model/cancel.h"
#include "model/error.h"
#include "model/parallel.h"
#include "tests/test_util.h"

namespace zwidth::analysis {
namespace {

struct Fleet {
  test::TempDir dir;
  std::vector<io::BatchEntry> units;
  explicit Fleet(int n) {
    for (int i = 0; i < n; ++i) {
      const std::string p = dir.Write("u" + std::to_string(i) + ".csv", "log " + std::to_string(i));
      units.push_back({"S" + std::to_string(i), p, {}, "unit " + std::to_string(i)});
    }
  }
};

RunInput Table1Input() {
  RunInput in;
  in.model = io::Table1Model();
  in.fit.status = fit::FitStatus::kConverged;
  in.response.frf.sample_rate_hz = 1000.0;
  return in;
}

// The engine (RunBatchWith) with a fake estimate and fit: Analyse of what `ef` hands.
template <class EstimateFit>
BatchResult RunFake(const std::vector<io::BatchEntry>& units, const BatchOptions& o, const EstimateFit& ef) {
  return RunBatchWith(units, o, [&](const io::BatchEntry& u, const RunOptions& ro) {
    RunOptions uo = ro;
    return Analyse(ef(u, &uo), uo);
  });
}

BatchOptions Options(int threads) {
  BatchOptions o;
  o.run.delays = {2};
  o.run.grid.b_points = 5;
  o.threads = threads;
  o.options_key = "--delays=2";
  return o;
}

TEST(RunBatch, AUnitsErrorIsItsRowAndTheOthersGoOn) {
  Fleet f(5);
  auto ef = [](const io::BatchEntry& u, RunOptions*) -> RunInput {
    if (u.serial == "S1") throw InputError("S1: no such column");
    if (u.serial == "S3") throw ComputationError("the fit did not converge");
    if (u.serial == "S4") throw std::runtime_error("something else");
    return Table1Input();
  };
  const BatchResult r = RunFake(f.units, Options(2), ef);
  ASSERT_EQ(r.table.rows.size(), 5u);
  const char* status[] = {"ok", "input_error", "ok", "computation_error", "computation_error"};
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(r.table.rows[i].at("serial"), f.units[i].serial);  // the units' order
    EXPECT_EQ(r.table.rows[i].at("status"), status[i]) << i;
  }
  EXPECT_EQ(r.table.rows[1].at("error"), "S1: no such column");
  EXPECT_EQ(r.table.rows[4].at("error"), "something else");
  EXPECT_EQ(r.progress.failed, 3u);
  EXPECT_EQ(r.progress.computed, 5u);
  // An ok row holds the model's parameters to 17 digits.
  EXPECT_EQ(std::stod(r.table.rows[0].at("m")), io::Table1Model().plant.m);
  EXPECT_EQ(r.table.rows[0].at("modes"), std::to_string(io::Table1Model().plant.modes.size()));
}

TEST(RunBatch, TheTableDoesNotDependOnTheThreadsAndEachUnitRunsSerial) {
  Fleet f(6);
  std::atomic<int> running{0}, most{0}, inner_threads{0};
  auto ef = [&](const io::BatchEntry& u, RunOptions*) {
    const int now = ++running;
    for (int m = most; now > m && !most.compare_exchange_weak(m, now);) {
    }
    inner_threads = std::max(inner_threads.load(), NumThreads());
    if (u.serial == "S2") {
      --running;
      throw InputError("bad");
    }
    RunInput in = Table1Input();
    in.model.plant.m *= 1.0 + 0.01 * std::stoi(u.serial.substr(1));  // a scatter, so rows differ
    --running;
    return in;
  };
  const std::string one = io::FormatBatchCsv(RunFake(f.units, Options(1), ef).table);
  EXPECT_EQ(inner_threads.load(), NumThreads());  // one thread: the unit's own loops as usual
  most = 0;
  inner_threads = 0;
  const std::string three = io::FormatBatchCsv(RunFake(f.units, Options(3), ef).table);
  EXPECT_EQ(one, three);
  EXPECT_LE(most.load(), 3);
  EXPECT_EQ(inner_threads.load(), 1);  // several units at once: each on its thread alone
}

TEST(RunBatch, AReRunTakesUnitsWithTheSameHashAndComputesChangedOnes) {
  Fleet f(3);
  std::atomic<int> calls{0};
  auto ef = [&](const io::BatchEntry&, RunOptions*) {
    ++calls;
    return Table1Input();
  };
  BatchOptions o = Options(2);
  const BatchResult first = RunFake(f.units, o, ef);
  EXPECT_EQ(calls.load(), 3);
  o.previous = first.table;
  calls = 0;
  const BatchResult again = RunFake(f.units, o, ef);
  EXPECT_EQ(calls.load(), 0);
  EXPECT_EQ(again.progress.resumed, 3u);
  EXPECT_EQ(io::FormatBatchCsv(again.table), io::FormatBatchCsv(first.table));
  std::ofstream(f.units[1].path, std::ios::app) << " changed";
  calls = 0;
  EXPECT_EQ(RunFake(f.units, o, ef).progress.resumed, 2u);
  EXPECT_EQ(calls.load(), 1);
  o.options_key = "--delays=4";
  calls = 0;
  RunFake(f.units, o, ef);
  EXPECT_EQ(calls.load(), 3);
  // A unit's own log flags are options too.
  o.options_key = "--delays=2";
  o.previous = RunFake(f.units, o, ef).table;
  std::vector<io::BatchEntry> flagged = f.units;
  flagged[0].flags = {{"rate", "2000"}};
  calls = 0;
  RunFake(flagged, o, ef);
  EXPECT_EQ(calls.load(), 1);
  // The friction model is in the key whether or not the caller's key spells it
  // out: a table of a batch that fitted no friction is not taken for one that does.
  ASSERT_EQ(o.estimate_fit.friction, fit::FrictionModel::kAuto);  // run's default
  o.previous = RunFake(f.units, o, ef).table;
  BatchOptions none = o;
  none.estimate_fit.friction = fit::FrictionModel::kNone;
  calls = 0;
  none.previous = RunFake(f.units, none, ef).table;
  EXPECT_EQ(calls.load(), 3);
  calls = 0;
  RunFake(f.units, none, ef);
  EXPECT_EQ(calls.load(), 0);
}

TEST(RunBatch, ACancelStopsTheBatchInsteadOfBecomingARow) {
  Fleet f(4);
  auto ef = [](const io::BatchEntry& u, RunOptions*) -> RunInput {
    if (u.serial == "S1") throw Cancelled();
    return Table1Input();
  };
  EXPECT_THROW(RunFake(f.units, Options(1), ef), Cancelled);
  BatchOptions bad = Options(1);
  bad.threads = -1;
  EXPECT_THROW(RunFake(f.units, bad, ef), InputError);
}

}  // namespace
}  // namespace zwidth::analysis
