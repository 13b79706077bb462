// Device logs: a torque input and an encoder position output, uniformly
// sampled. Three formats, told apart by content (not by extension):
//   text - delimited columns as labs write them: comma, semicolon, tab or
//          whitespace (detected from the first data line, or given); '#'
//          comment lines skipped; the header is the last line before the data
//          and may carry the comment mark (numpy genfromtxt names=True); UTF-8
//          BOM; LF, CRLF or CR line ends. Columns by name or 1-based position
//          (default t,torque,position; s, N m, rad);
//   HDF5 - datasets /time, /input/torque, /output/position and a root attribute
//          sample_rate_hz (units as attributes).
// Readers validate as they go and throw InputError naming the file, the row or
// dataset, and what to do. Logs are streamed in chunks, so a consumer such as
// the Welch estimator needs memory for a few windows, not for the whole log.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>
#include "model/sample_period.h"

namespace zwidth::io {

struct LogSelect {
  // Text columns: a header name (exact, else case-insensitive) or a 1-based
  // position; time_column "none" means no time column (then --rate).
  std::string time_column = "t";           // text
  std::string input_column = "torque";     // text
  std::string output_column = "position";  // text
  // Field separator of a text log: "" detects it (';', tab, ',', then runs of
  // whitespace, the first that splits the first data line into >= 2 numbers);
  // else one of ",", ";", "tab", "space" (runs of blanks), or one character.
  std::string delimiter;
  // Multiplies the input / output samples (e.g. counts -> rad); finite, != 0.
  double input_scale = 1.0;
  double output_scale = 1.0;
  // Unit of the text time column: "s", "ms" or "us"; "" = s, and then an
  // implied rate outside [10 Hz, 1 MHz] is refused with a suggestion.
  std::string time_unit;
  // Units of the input and output columns (io/log_units.h): "" reads them
  // from the header (a bracketed unit, a known suffix such as _deg, or a units
  // row under the header), else SI; "si" takes the column as SI; or a unit
  // such as "mN m", "deg", "mm", "counts". The samples are converted to N m
  // or N, and rad or m, before input_scale / output_scale multiply them.
  std::string input_unit, output_unit;
  // Encoder resolution for an output in counts: counts per turn (rotary, to
  // rad) or per metre (linear, to m); 0 = not given.
  double counts_per_rev = 0.0, counts_per_m = 0.0;
  // Numbers of a text log use ',' as the decimal mark ("0,25"); without it a
  // file whose first data line reads only that way is detected as such.
  bool decimal_comma = false;
  std::string time_dataset = "/time";                 // HDF5
  std::string input_dataset = "/input/torque";        // HDF5
  std::string output_dataset = "/output/position";    // HDF5
  // Overrides the rate found in the file when > 0 [Hz]; needed for a text log
  // without a time column. With a time column, the column is then only checked
  // to increase, and its jitter against 1/rate is reported as a warning.
  double sample_rate_hz = 0.0;
  // Allowed deviation of one sampling interval from the mean interval so far
  // (relative). Real loggers jitter by ~1e-5; a dropped sample deviates by 1.
  double max_interval_deviation = 0.01;
};

// The axis a text log's header gives its input and output columns (a unit
// of io/log_units.h's table found in the header: "force [N]", "pos_mm", a
// units row; not one given by LogSelect::input_unit / output_unit): rotary
// (N m, rad, deg, ...), linear (N, m, mm, ...), both (the two columns
// disagree), or none said.
enum class HeaderUnits { kNone, kRotary, kLinear, kMixed };

struct LogInfo {
  std::string source;
  size_t num_samples = 0;
  double sample_rate_hz = 0.0;
  double period_s() const { return model::SamplePeriod(sample_rate_hz); }  // the sample period T [s]
  // How the file was read, e.g. "text, ';'-separated, header at line 3
  // (comment): t, torque, position; columns 1, 2, 3".
  std::string layout;
  std::vector<std::string> warnings;  // e.g. the time column's jitter under --rate
  HeaderUnits header_units = HeaderUnits::kNone;
  // What the header said, e.g. "input 'force [N]' in N, output 'x [m]' in m"; "" for kNone.
  std::string header_units_text;
};

// Whether a fit of logs read with these infos is of a linear axis: the
// caller's choice (`given`: ModelFile::linear from --units / units=) when
// made, else what the headers say, else rotary. Throws InputError, naming the
// log and `option` (the field that gives the choice), for a header whose
// columns mix rotary and linear units, logs whose headers disagree, or a
// header that contradicts `given`.
bool LinearUnitsOf(std::optional<bool> given, const std::vector<LogInfo>& infos, const std::string& option);

enum class LogFormat { kCsv, kHdf5, kMat };
// By content: the HDF5 signature (also MATLAB v7.3, whose 512-byte user block
// precedes it), the 128-byte MATLAB v5 header, else text.
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
  double period_s() const { return info.period_s(); }  // the sample period T [s]
};
Log ReadLog(const std::string& path, const LogSelect& select = {});

// A 64-bit fingerprint (FNV-1a) of a log's samples as read, whatever the
// format: two logs with the same fingerprint hold the same data (the same
// file, a copy, a link, or the same samples saved as .h5 and .csv). Runs of one
// device are averaged as independent; the same data twice would shrink every
// per-bin std by 1/sqrt(2) while adding nothing, so the estimate refuses it.
class LogFingerprint {
 public:
  void Add(const double* input, const double* output, size_t n);
  std::uint64_t value() const { return hu_ ^ (hy_ * 31) ^ n_; }  // whatever the chunks were

 private:
  std::uint64_t hu_ = 14695981039346656037ull, hy_ = 14695981039346656037ull, n_ = 0;
};

using model::IsDeviceLogRate;  // the readers' range of a rate (model/sample_period.h)

// What the readers refuse in the samples they read, for a log made in memory
// (Python's zwidth.Log, a simulated one): input and output of one length, every
// sample finite, a rate in (10 Hz, 1 MHz] (the readers' range of a device log),
// an input and an output that vary (a constant one, or a single sample, has
// nothing to identify from). InputError naming `source` and the first problem.
void CheckLogSamples(double sample_rate_hz, const std::vector<double>& input, const std::vector<double>& output,
                     const std::string& source);

// Writers (atomic), after CheckLogSamples: never a file the readers refuse.
// time may be empty: then t = k / sample_rate_hz. linear: a linear axis's log
// (force [N], position [m]); a text log's header then says so
// ("t,force [N],position [m]", read back with LogSelect::input_column "force");
// rotary: "t,torque,position".
void WriteLog(const std::string& path, double sample_rate_hz,
              const std::vector<double>& input, const std::vector<double>& output, bool linear = false);

}  // namespace zwidth::io
