// Device logs: a torque input and an encoder position output, uniformly
// sampled. Two formats:
//   CSV  - header naming the columns (default t,torque,position; s, N m, rad);
//   HDF5 - datasets /time, /input/torque, /output/position and a root attribute
//          sample_rate_hz (units as attributes).
// Readers validate as they go and throw InputError naming the file, the row or
// dataset, and what to do. Logs are streamed in chunks, so a consumer such as
// the Welch estimator needs memory for a few windows, not for the whole log.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace zwidth::io {

struct LogSelect {
  std::string time_column = "t";           // CSV
  std::string input_column = "torque";     // CSV
  std::string output_column = "position";  // CSV
  std::string time_dataset = "/time";                 // HDF5
  std::string input_dataset = "/input/torque";        // HDF5
  std::string output_dataset = "/output/position";    // HDF5
  // Overrides the rate found in the file when > 0 [Hz]; needed for a CSV
  // without a time column.
  double sample_rate_hz = 0.0;
  // Allowed deviation of one sampling interval from the mean interval so far
  // (relative). Real loggers jitter by ~1e-5; a dropped sample deviates by 1.
  double max_interval_deviation = 0.01;
};

struct LogInfo {
  std::string source;
  size_t num_samples = 0;
  double sample_rate_hz = 0.0;
};

enum class LogFormat { kCsv, kHdf5 };
// By extension (.csv/.txt, .h5/.hdf5/.he5), else by the HDF5 signature.
LogFormat DetectLogFormat(const std::string& path);

using LogSink = std::function<void(const double* input, const double* output, size_t n)>;

// The most samples a log may hold (2^30, 12 days at 1 kHz): more is refused
// before reading (HDF5) or when reached (CSV), never silently truncated.
inline constexpr size_t kMaxLogSamples = size_t{1} << 30;

// Streams (input, output) chunks to sink after validating them. Throws
// InputError on any problem; the sink may have seen earlier chunks by then.
LogInfo StreamLog(const std::string& path, const LogSelect& select, const LogSink& sink);

struct Log {
  LogInfo info;
  std::vector<double> input;   // N m (or the unit of the selected column)
  std::vector<double> output;  // rad
};
Log ReadLog(const std::string& path, const LogSelect& select = {});

// The HDF5 parsing that StreamLog runs in a child process (io/isolated.h),
// callable in this process for the fuzzer (the isolation is tested on its own).
namespace internal {
LogInfo StreamHdf5InProcess(const std::string& path, const LogSelect& select, const LogSink& sink);
}  // namespace internal

// Writers (atomic). time may be empty: then t = k / sample_rate_hz.
void WriteLog(const std::string& path, double sample_rate_hz,
              const std::vector<double>& input, const std::vector<double>& output);

}  // namespace zwidth::io
