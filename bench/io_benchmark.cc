// Reading the shipped 30 s HDF5 log (datasets/phantom/phantom_30s.h5, 30000
// samples): as zwidth does, parsed in a forked child (io/isolated.h) that
// streams the chunks back through a pipe, against parsed in this process; and
// the isolation alone (fork, pipe, one frame, wait) to see what it costs.
// error = |samples read - 30000| + the largest |difference| from the
// in-process read (0 when both read the same numbers).
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "io/isolated.h"
#include "io/log.h"
#include "io/log_internal.h"

namespace zwidth {
namespace {

const std::string kLog = std::string(ZWIDTH_SOURCE_DIR) + "/datasets/phantom/phantom_30s.h5";

io::Log InProcess() {
  io::Log log;
  log.info = io::internal::StreamHdf5InProcess(kLog, {}, [&](const double* u, const double* y, size_t n) {
    log.input.insert(log.input.end(), u, u + n);
    log.output.insert(log.output.end(), y, y + n);
  });
  return log;
}

double Error(const io::Log& log) {
  static const io::Log ref = InProcess();
  double e = std::abs(static_cast<double>(log.input.size()) - 30000.0);
  if (log.input.size() != ref.input.size()) return e + INFINITY;
  for (size_t k = 0; k < log.input.size(); ++k) {
    e = std::max({e, std::abs(log.input[k] - ref.input[k]), std::abs(log.output[k] - ref.output[k])});
  }
  return e;
}

// range(0): 0 = in this process (StreamHdf5InProcess), 1 = in a forked child (io::ReadLog).
void BM_ReadHdf5Log(benchmark::State& state) {
  io::Log log;
  for (auto _ : state) {
    log = state.range(0) ? io::ReadLog(kLog, {}) : InProcess();
    benchmark::DoNotOptimize(log.input.data());
  }
  state.counters["error"] = Error(log);
  state.SetLabel(state.range(0) ? "forked child (zwidth's way)" : "in process");
}
BENCHMARK(BM_ReadHdf5Log)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The isolation without the read: fork, a one-byte frame back, waitpid.
void BM_IsolationOnly(benchmark::State& state) {
  size_t got = 0;
  for (auto _ : state) {
    io::RunIsolated(
        kLog, [](const io::FrameSender& send) { const char b = 1; send(&b, 1); },
        [&](std::string_view f) { got += f.size(); });
  }
  state.counters["error"] = std::abs(static_cast<double>(got) - static_cast<double>(state.iterations()));
}
BENCHMARK(BM_IsolationOnly)->Unit(benchmark::kMicrosecond);

// The read in a forked child that sends back only the sample count: the
// child's share of BM_ReadHdf5Log/1 without the transfer through the pipe.
void BM_ReadHdf5LogInChildNoTransfer(benchmark::State& state) {
  size_t n = 0;
  for (auto _ : state) {
    io::RunIsolated(
        kLog,
        [](const io::FrameSender& send) {
          const size_t count = InProcess().input.size();
          send(&count, sizeof count);
        },
        [&](std::string_view f) { std::memcpy(&n, f.data(), sizeof n); });
  }
  state.counters["error"] = std::abs(static_cast<double>(n) - 30000.0);
}
BENCHMARK(BM_ReadHdf5LogInChildNoTransfer)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace zwidth
