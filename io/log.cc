#include "io/log.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <memory>
#include <sstream>

#include <sys/stat.h>

#include "io/atomic_file.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "io/log_internal.h"
#include "io/isolated.h"
#include "model/c_locale.h"
#include "model/error.h"


namespace zwidth::io {
namespace internal {

LogInfo StreamIsolatedLog(const std::string& path, const std::string& what, const LogSelect& sel,
                          const LogSink& sink,
                          LogInfo (*parse)(const std::string&, const LogSelect&, const LogSink&)) {
  LogInfo info;
  bool ended = false;
  std::vector<double> u, y;
  RunIsolated(
      path,
      [&](const FrameSender& send) {
        std::vector<char> frame;
        const LogInfo in = parse(path, sel, [&](const double* cu, const double* cy, size_t n) {
          frame.resize(1 + 2 * n * sizeof(double));
          frame[0] = 'c';
          std::memcpy(frame.data() + 1, cu, n * sizeof(double));
          std::memcpy(frame.data() + 1 + n * sizeof(double), cy, n * sizeof(double));
          send(frame.data(), frame.size());
        });
        const uint64_t count = in.num_samples;
        char end[1 + sizeof count + sizeof in.sample_rate_hz] = {'i'};
        std::memcpy(end + 1, &count, sizeof count);
        std::memcpy(end + 1 + sizeof count, &in.sample_rate_hz, sizeof in.sample_rate_hz);
        send(end, sizeof end);
      },
      [&](std::string_view f) {
        if (!f.empty() && f[0] == 'c' && (f.size() - 1) % (2 * sizeof(double)) == 0) {
          const size_t n = (f.size() - 1) / (2 * sizeof(double));
          u.resize(n);
          y.resize(n);
          std::memcpy(u.data(), f.data() + 1, n * sizeof(double));
          std::memcpy(y.data(), f.data() + 1 + n * sizeof(double), n * sizeof(double));
          sink(u.data(), y.data(), n);
        } else if (f.size() == 1 + sizeof(uint64_t) + sizeof(double) && f[0] == 'i') {
          uint64_t count = 0;
          std::memcpy(&count, f.data() + 1, sizeof count);
          std::memcpy(&info.sample_rate_hz, f.data() + 1 + sizeof count, sizeof(double));
          info.source = path;
          info.num_samples = count;
          ended = true;
        } else {
          throw InputError(path + ": could not read the " + what + " (corrupt or truncated?)");
        }
      });
  if (!ended) throw InputError(path + ": could not read the " + what + " (corrupt or truncated?)");
  return info;
}

// The binary formats are parsed in a child process (io/isolated.h) that
// streams the chunks through a pipe: a crash in libhdf5 or libmatio becomes an
// InputError here, and the data is still read once, in bounded memory.
LogInfo StreamHdf5(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  return StreamIsolatedLog(path, "HDF5 file", sel, sink, Hdf5().stream_hdf5_log);
}

LogInfo StreamMat(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  LogInfo info = StreamIsolatedLog(path, ".mat file", sel, sink, Hdf5().stream_mat_log);
  info.layout = "MATLAB .mat (libmatio)";
  return info;
}

}  // namespace internal

using namespace internal;


LogFormat DetectLogFormat(const std::string& path) {
  // Only a regular file is opened to sniff (a FIFO or a device would block or
  // never end); anything else is classified by name and refused by its reader.
  struct stat st;
  const bool regular = ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
  std::ifstream in;
  if (regular) in.open(path, std::ios::binary);
  if (!regular || !in) {  // not there (a file to write): by extension
    return HasExtension(path, {".h5", ".hdf5", ".he5"}) ? LogFormat::kHdf5
           : HasExtension(path, {".mat"})                 ? LogFormat::kMat
                                                          : LogFormat::kCsv;
  }
  char head[2056] = {};
  in.read(head, sizeof head);
  const size_t got = static_cast<size_t>(in.gcount());
  // MATLAB v5 and v7.3 (whose HDF5 part follows): 116 bytes of text starting "MATLAB 5.0 MAT-file" (or 7.3), version
  // 0x0100 and the endian mark "IM" or "MI" at bytes 124..127.
  if (got >= 128 && std::memcmp(head, "MATLAB", 6) == 0 &&
      (std::memcmp(head + 126, "IM", 2) == 0 || std::memcmp(head + 126, "MI", 2) == 0)) {
    return LogFormat::kMat;
  }
  // HDF5 signature at 0 or after a user block of 512, 1024 or 2048 bytes
  // (MATLAB v7.3 files have a 512-byte one holding the MAT header).
  for (size_t off : {0, 512, 1024, 2048}) {
    if (got >= off + 8 && std::memcmp(head + off, "\x89HDF\r\n\x1a\n", 8) == 0) return LogFormat::kHdf5;
  }
  return LogFormat::kCsv;
}

// A text log is UTF-8 (or ASCII): a UTF-16 or UTF-32 file (Windows' "Unicode"
// text: a byte-order mark, or a NUL beside every ASCII character) is named as
// such with the conversion, instead of "no numeric data row".
static void CheckTextEncoding(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[4096];
  in.read(reinterpret_cast<char*>(head), sizeof head);
  const size_t n = static_cast<size_t>(in.gcount());
  const bool bom32 = n >= 4 && ((head[0] == 0xFF && head[1] == 0xFE && head[2] == 0 && head[3] == 0) ||
                                (head[0] == 0 && head[1] == 0 && head[2] == 0xFE && head[3] == 0xFF));
  const bool bom16 = !bom32 && n >= 2 && ((head[0] == 0xFF && head[1] == 0xFE) || (head[0] == 0xFE && head[1] == 0xFF));
  size_t nul_even = 0, nul_odd = 0;
  for (size_t i = 0; i < n; ++i) {
    if (head[i] == 0) ++(i % 2 ? nul_odd : nul_even);
  }
  const bool alternating = n >= 16 && std::max(nul_even, nul_odd) >= n / 2 - 2 && std::min(nul_even, nul_odd) == 0;
  if (!bom32 && !bom16 && !alternating && nul_even + nul_odd > 0 && HasExtension(path, {".mat"})) {
    throw InputError(path + ": a binary .mat file without the MATLAB v5/v7/v7.3 header: a MATLAB v4 file (save -v4) "
                     "or another format, which zwidth does not read: save it again with save -v7");
  }
  if (!bom32 && !bom16 && !alternating) return;
  const char* enc = bom32 ? "UTF-32" : "UTF-16";
  throw InputError(path + ": a " + std::string(enc) + " text file; zwidth reads text logs in UTF-8 or ASCII: convert "
                   "it (iconv -f " + enc + " -t UTF-8 FILE > FILE.csv, or save as 'CSV UTF-8')");
}

LogInfo StreamLog(const std::string& path, const LogSelect& select, const LogSink& sink) {
  if (select.sample_rate_hz < 0.0 || !std::isfinite(select.sample_rate_hz)) {
    throw InputError("LogSelect::sample_rate_hz must be finite and > 0");
  }
  if (select.sample_rate_hz > 0.0 && !IsDeviceLogRate(select.sample_rate_hz)) {  // as a rate read from the file
    throw InputError("LogSelect::sample_rate_hz = " + FormatG(select.sample_rate_hz) +
                     " Hz: outside 10 Hz..1 MHz (10 excluded), the rates of a device log; is it the period? then "
                     "give 1 / period");
  }
  for (const auto& [v, flag] : {std::pair{select.input_scale, "LogSelect::input_scale"}, std::pair{select.output_scale, "LogSelect::output_scale"}}) {
    if (!std::isfinite(v) || v == 0.0) {
      throw InputError(std::string(flag) + " = " + std::to_string(v) + ": must be finite and non-zero");
    }
  }
  TimeScale(select.time_unit);  // validates the flag
  for (const auto& [v, flag] : {std::pair{select.counts_per_rev, "LogSelect::counts_per_rev"}, std::pair{select.counts_per_m, "LogSelect::counts_per_m"}}) {
    if (!std::isfinite(v) || v < 0.0) throw InputError(std::string(flag) + " = " + std::to_string(v) + ": must be finite and > 0");
  }
  CheckInputFile(path, "log");
  size_t total = 0;
  internal::ConstantCheck output_constant;
  const LogSink capped = [&](const double* u, const double* y, size_t n) {
    total += n;
    if (total > kMaxLogSamples) {
      throw InputError(path + ": more than " + std::to_string(kMaxLogSamples) +
                       " samples, more than zwidth reads; split the log");
    }
    output_constant.Add(y, n);
    sink(u, y, n);
  };
  const LogFormat format = DetectLogFormat(path);
  // A constant output (an encoder not read, the wrong column) would give a
  // response of zeros and a coherence of 0/0: said here, as for the input.
  auto check_output = [&](LogInfo info) {
    if (!output_constant.varies) {
      const bool h5 = format == LogFormat::kHdf5;
      std::ostringstream os;
      os.precision(6);
      os << path << ": output " << (h5 ? "dataset '" + select.output_dataset.substr(0, 40) + "'"
                                       : "column '" + select.output_column.substr(0, 40) + "'")
         << " is constant (every sample " << output_constant.first / select.output_scale
         << "): the device did not move or its sensor was not read (wrong "
         << (h5 ? "LogSelect::output_dataset" : "LogSelect::output_column") << "? sensor unplugged?)";
      throw InputError(os.str());
    }
    return info;
  };
  if (format == LogFormat::kCsv) {
    CheckTextEncoding(path);
    return check_output(StreamCsv(path, select, capped));
  }
  if (!select.time_unit.empty() && select.time_unit != "s") {
    throw InputError(path + ": LogSelect::time_unit applies to text logs; this " +
                     std::string(format == LogFormat::kMat ? "MATLAB" : "HDF5") +
                     " log's time is read in s (give LogSelect::sample_rate_hz instead)");
  }
  // Scales applied here for the binary formats (the text reader applies them).
  std::vector<double> su, sy;
  const LogSink scaled = [&](const double* u, const double* y, size_t n) {
    su.assign(u, u + n);
    sy.assign(y, y + n);
    for (double& v : su) v *= select.input_scale;
    for (double& v : sy) v *= select.output_scale;
    capped(su.data(), sy.data(), n);
  };
  LogInfo info = format == LogFormat::kMat ? StreamMat(path, select, scaled) : StreamHdf5(path, select, scaled);
  if (info.layout.empty()) info.layout = format == LogFormat::kMat ? "MATLAB v5 .mat" : "HDF5";
  // The text reader's plausibility range (log_text.cc), for time read in s.
  if (select.sample_rate_hz <= 0.0 && info.sample_rate_hz > 0.0) {
    const double r = info.sample_rate_hz;
    std::ostringstream os;
    os.precision(4);
    os << "the log's time implies " << r << " Hz";
    const std::string hint = "; a " + std::string(format == LogFormat::kMat ? ".mat" : "HDF5") +
                             " log's time is read in s: if it is in ms, LogSelect::sample_rate_hz " +
                             [&] { std::ostringstream h; h.precision(4); h << r * 1e3; return h.str(); }() +
                             " gives the rate";
    if (!IsDeviceLogRate(r)) {
      throw InputError(path + ": " + os.str() + ", implausible for a device log (10 Hz..1 MHz)" + hint);
    }
    if (r < 100.0) info.warnings.push_back(os.str() + ", low for a haptic device log" + hint);
  }
  return check_output(std::move(info));
}

bool LinearUnitsOf(std::optional<bool> given, const std::vector<LogInfo>& infos, const std::string& option) {
  auto word = [](bool linear) { return std::string(linear ? "linear" : "rotary"); };
  const LogInfo* said = nullptr;  // the first log whose header says an axis
  for (const LogInfo& info : infos) {
    if (info.header_units == HeaderUnits::kMixed) {
      throw InputError(info.source + ": the header mixes rotary and linear units (" + info.header_units_text +
                       "): a model is of one axis; correct the header, or give each column's unit with "
                       "LogSelect::input_unit and LogSelect::output_unit");
    }
    if (info.header_units == HeaderUnits::kNone) continue;
    const bool linear = info.header_units == HeaderUnits::kLinear;
    if (given && *given != linear) {
      throw InputError(info.source + ": the header says " + word(linear) + " units (" + info.header_units_text +
                       ") but " + option + " " + word(*given) + " was given: pass " + option + " " + word(linear) +
                       " (or none: the header's), or correct the header");
    }
    if (said && (said->header_units == HeaderUnits::kLinear) != linear) {
      throw InputError(info.source + ": the header says " + word(linear) + " units (" + info.header_units_text +
                       ") but " + said->source + "'s says " + word(!linear) + " (" + said->header_units_text +
                       "): the runs of one device have one axis; fit them apart, or correct the header");
    }
    if (!said) said = &info;
  }
  if (given) return *given;
  return said && said->header_units == HeaderUnits::kLinear;
}

void LogFingerprint::Add(const double* input, const double* output, size_t n) {
  auto add = [n](const double* v, std::uint64_t* h) {
    const unsigned char* b = reinterpret_cast<const unsigned char*>(v);
    for (size_t k = 0; k < n * sizeof(double); ++k) *h = (*h ^ b[k]) * 1099511628211ull;
  };
  add(input, &hu_);
  add(output, &hy_);
  n_ += n;
}

Log ReadLog(const std::string& path, const LogSelect& select) {
  Log log;
  log.info = StreamLog(path, select, [&](const double* u, const double* y, size_t n) {
    log.input.insert(log.input.end(), u, u + n);
    log.output.insert(log.output.end(), y, y + n);
  });
  return log;
}

void CheckLogSamples(double rate, const std::vector<double>& u, const std::vector<double>& y,
                     const std::string& source) {
  if (u.size() != y.size()) {
    throw InputError(source + ": the input (u) has " + std::to_string(u.size()) + " samples and the output (y) " +
                     std::to_string(y.size()) + ": they must have the same length");
  }
  if (!(std::isfinite(rate) && IsDeviceLogRate(rate))) {
    throw InputError(source + ": sample_rate_hz = " + FormatG(rate) + " Hz: the readers take 10 Hz..1 MHz (10 "
                     "excluded), the rates of a device log; is it the period? then give 1 / period");
  }
  for (const auto& [v, name] : {std::pair{&u, "input (u)"}, std::pair{&y, "output (y)"}}) {
    for (size_t k = 0; k < v->size(); ++k) {
      if (!std::isfinite((*v)[k])) {
        throw InputError(source + ": " + name + "[" + std::to_string(k) + "] = " + FormatG((*v)[k]) +
                         ": every sample must be finite");
      }
    }
    internal::ConstantCheck c;
    c.Add(v->data(), v->size());
    if (!c.varies) {
      throw InputError(source + ": the " + name + " is constant (" + std::to_string(v->size()) +
                       " samples): the readers refuse such a log, it has nothing to identify from");
    }
  }
}

void WriteLog(const std::string& path, double rate, const std::vector<double>& u,
              const std::vector<double>& y, bool linear) {
  CheckLogSamples(rate, u, y, path);
  // By extension: the file is about to be (re)written.
  const bool h5 = HasExtension(path, {".h5", ".hdf5", ".he5"});
  if (h5) {
    WriteHdf5Atomically(path, [&](const Hdf5Api& api, const std::string& tmp) { api.write_hdf5_log(tmp, rate, u, y); });
  } else {
    WriteAtomically(path, [&](const std::string& tmp) { WriteCsvLog(tmp, rate, u, y, linear); });
  }
}

}  // namespace zwidth::io

