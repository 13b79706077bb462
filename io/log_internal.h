// Internals of the log readers and writers, shared by io/log.cc (format
// detection, the child-process framing) and one file per format:
// log_text.cc (delimited text), log_mat.cc (MATLAB .mat), log_hdf5.cc.
// Not installed: include only from io/*.cc (and tests, benchmarks, the fuzzer).
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "io/log.h"
#include "model/error.h"

namespace zwidth::io::internal {

// The HDF5 parsing that StreamLog runs in a child process (io/isolated.h),
// callable in this process for the fuzzer (the isolation is tested on its own).
LogInfo StreamHdf5InProcess(const std::string& path, const LogSelect& select, const LogSink& sink);

constexpr size_t kChunk = 1 << 16;

inline std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Whether `path` ends with one of `exts` (".h5"), in any case: how a writer
// picks the format of a file it is about to (re)write.
inline bool HasExtension(const std::string& path, std::initializer_list<const char*> exts) {
  const std::string p = Lower(path);
  for (const char* s : exts) {
    const size_t n = std::strlen(s);
    if (p.size() >= n && p.compare(p.size() - n, n, s) == 0) return true;
  }
  return false;
}

// Checks the sampling-interval invariants on the stream of time stamps.
class TimeChecker {
 public:
  // uniform = false (a rate was given): only checks that time increases, and
  // records the extreme intervals.
  TimeChecker(std::string source, double tolerance, bool uniform = true)
      : source_(std::move(source)), tol_(tolerance), uniform_(uniform) {}
  void Add(double t, const std::string& where) {
    AddLazy(t, [&] { return where; });
  }
  // where() is called only to word an error.
  template <class Where>
  void AddLazy(double t, const Where& where) {
    if (n_ > 0) {
      const double dt = t - last_;
      if (!(dt > 0.0)) {
        std::ostringstream os;
        os.precision(12);
        os << source_ << ": time is not strictly increasing at " << where() << " (t = " << t
           << " after " << last_ << ")";
        throw InputError(os.str());
      }
      min_dt_ = std::min(min_dt_, dt);
      max_dt_ = std::max(max_dt_, dt);
      if (n_ >= 2 && uniform_ && !violation_) {
        const double mean = (last_ - first_) / static_cast<double>(n_ - 1);
        // The first interval off the mean so far is kept, and refused when the
        // rate is asked for, against the whole log's mean interval.
        if (std::abs(dt - mean) > tol_ * mean) violation_ = Violation{where(), dt};
      }
    } else {
      first_ = t;
    }
    last_ = t;
    ++n_;
  }
  // The mean rate of the time stamps (0 with fewer than 2); throws the first
  // non-uniform interval (uniform = true) as an InputError.
  double Rate() const {
    if (violation_) {
      const double mean = (last_ - first_) / static_cast<double>(n_ - 1);
      std::ostringstream os;
      os.precision(6);
      os << source_ << ": not uniformly sampled at " << violation_->where << ": interval " << violation_->dt
         << " s differs from the log's mean interval " << mean << " s by "
         << 100.0 * std::abs(violation_->dt - mean) / mean
         << " % (missing or repeated samples?); if only the time stamps jitter, LogSelect::sample_rate_hz "
         << 1.0 / mean << " (the log's mean rate) reads it at that rate and only checks that time increases; "
         << "else resample the log";
      throw InputError(os.str());
    }
    return n_ >= 2 ? static_cast<double>(n_ - 1) / (last_ - first_) : 0.0;
  }
  double MinInterval() const { return min_dt_; }
  double MaxInterval() const { return max_dt_; }

 private:
  std::string source_;
  double tol_;
  bool uniform_ = true;
  double min_dt_ = std::numeric_limits<double>::infinity(), max_dt_ = 0.0;
  double first_ = 0.0, last_ = 0.0;
  size_t n_ = 0;
  struct Violation {
    std::string where;
    double dt;
  };
  std::optional<Violation> violation_;
};

inline void CheckFinite(double v, const std::string& source, const std::string& where) {
  if (!std::isfinite(v)) {
    throw InputError(source + ": non-finite value (" + std::to_string(v) + ") at " + where +
                     "; remove or repair that row");
  }
}

// Tracks whether the input ever changes.
struct ConstantCheck {
  double first = 0.0;
  bool any = false, varies = false;
  void Add(const double* u, size_t n) {
    for (size_t i = 0; i < n && !varies; ++i) {
      if (!any) { first = u[i]; any = true; }
      else if (u[i] != first) varies = true;
    }
  }
};

// The time unit's scale to seconds (s, ms, us); InputError otherwise.
double TimeScale(const std::string& unit);

LogInfo StreamCsv(const std::string& path, const LogSelect& sel, const LogSink& sink);
LogInfo StreamMat(const std::string& path, const LogSelect& sel, const LogSink& sink);
LogInfo StreamHdf5(const std::string& path, const LogSelect& sel, const LogSink& sink);
void WriteCsvLog(const std::string& tmp, double rate, const std::vector<double>& u, const std::vector<double>& y,
                 bool linear = false);
void WriteHdf5Log(const std::string& tmp, double rate, const std::vector<double>& u, const std::vector<double>& y);

// A binary log parsed in a child process (io/isolated.h): `parse` runs there and its
// chunks come back framed 'c' u[n] y[n], then 'i' count rate. `what` names the
// format in errors.
LogInfo StreamIsolatedLog(const std::string& path, const std::string& what, const LogSelect& sel,
                          const LogSink& sink,
                          LogInfo (*parse)(const std::string&, const LogSelect&, const LogSink&));

}  // namespace zwidth::io::internal
