#include "io/log.h"

#include <algorithm>
#include <charconv>
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

#include <H5Cpp.h>
#include <matio.h>

#include "io/atomic_file.h"
#include "io/h5_safety.h"
#include "io/io_internal.h"
#include "io/isolated.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

constexpr size_t kChunk = 1 << 16;

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
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
      if (n_ >= 2 && uniform_) {
        const double mean = (last_ - first_) / static_cast<double>(n_ - 1);
        if (std::abs(dt - mean) > tol_ * mean) {
          std::ostringstream os;
          os.precision(6);
          os << source_ << ": not uniformly sampled at " << where() << ": interval " << dt
             << " s differs from the mean interval " << mean << " s by "
             << 100.0 * std::abs(dt - mean) / mean
             << "% (missing or repeated samples?); resample the log first";
          throw InputError(os.str());
        }
      }
    } else {
      first_ = t;
    }
    last_ = t;
    ++n_;
  }
  double Rate() const { return n_ >= 2 ? static_cast<double>(n_ - 1) / (last_ - first_) : 0.0; }
  double MinInterval() const { return min_dt_; }
  double MaxInterval() const { return max_dt_; }

 private:
  std::string source_;
  double tol_;
  bool uniform_ = true;
  double min_dt_ = std::numeric_limits<double>::infinity(), max_dt_ = 0.0;
  double first_ = 0.0, last_ = 0.0;
  size_t n_ = 0;
};

void CheckFinite(double v, const std::string& source, const std::string& where) {
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

// ---- Delimited text -------------------------------------------------------

constexpr size_t kMaxLine = 1 << 20;         // longer lines: not a text log
constexpr size_t kMaxPreambleLines = 10000;  // lines before the first data row
constexpr size_t kShown = 80;                // characters of a line a message may show

// At most kShown characters of one line, non-printables escaped.
std::string Shown(std::string_view s) {
  std::string o;
  for (size_t i = 0; i < s.size() && o.size() < kShown; ++i) {
    const unsigned char c = s[i];
    if (c >= 0x20 && c < 0x7f) o += static_cast<char>(c);
    else if (c == '\t') o += "\\t";
    else {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", c);
      o += b;
    }
  }
  if (o.size() >= kShown || s.size() > kShown) o += "...";
  return "'" + o + "'";
}

// Lines ending in LF, CRLF or CR, read in blocks.
class LineReader {
 public:
  LineReader(std::istream& in, std::string path) : in_(in), path_(std::move(path)), buf_(1 << 16) {}
  bool Next(std::string* line) {
    line->clear();
    bool any = false;
    while (true) {
      if (pos_ == end_) {
        if (!in_) break;
        in_.read(buf_.data(), static_cast<std::streamsize>(buf_.size()));
        end_ = static_cast<size_t>(in_.gcount());
        pos_ = 0;
        if (in_.bad()) throw InputError(path_ + ": read error");
        if (end_ == 0) break;
      }
      if (skip_lf_) {
        skip_lf_ = false;
        if (buf_[pos_] == '\n') { ++pos_; continue; }
      }
      size_t i = pos_;
      while (i < end_ && buf_[i] != '\n' && buf_[i] != '\r') ++i;
      line->append(buf_.data() + pos_, i - pos_);
      any = true;
      if (line->size() > kMaxLine) {
        throw InputError(path_ + ": line " + std::to_string(line_no_ + 1) + " is longer than " +
                         std::to_string(kMaxLine) + " bytes: not a text log (binary file?)");
      }
      if (i < end_) {
        skip_lf_ = buf_[i] == '\r';
        pos_ = i + 1;
        ++line_no_;
        return true;
      }
      pos_ = end_;
    }
    if (any) ++line_no_;
    return any;
  }
  size_t line_no() const { return line_no_; }

 private:
  std::istream& in_;
  std::string path_;
  std::vector<char> buf_;
  size_t pos_ = 0, end_ = 0, line_no_ = 0;
  bool skip_lf_ = false;
};

// A field separator: one character, or runs of blanks (ws).
struct Delim {
  char c = ',';
  bool ws = false;
  std::string Name() const {
    if (ws) return "whitespace";
    if (c == '\t') return "tab";
    return std::string("'") + c + "'";
  }
};

std::string_view TrimView(std::string_view f) {
  while (!f.empty() && (f.front() == ' ' || f.front() == '\t' || f.front() == '"')) f.remove_prefix(1);
  while (!f.empty() && (f.back() == ' ' || f.back() == '\t' || f.back() == '"')) f.remove_suffix(1);
  return f;
}

void Split(std::string_view sv, const Delim& d, std::vector<std::string_view>* out) {
  out->clear();
  if (d.ws) {
    size_t i = 0;
    while (true) {
      while (i < sv.size() && (sv[i] == ' ' || sv[i] == '\t')) ++i;
      if (i >= sv.size()) break;
      size_t j = i;
      while (j < sv.size() && sv[j] != ' ' && sv[j] != '\t') ++j;
      out->push_back(TrimView(sv.substr(i, j - i)));
      i = j;
    }
    return;
  }
  internal::SplitFields(sv, d.c, out);
  for (std::string_view& f : *out) f = TrimView(f);
  // A trailing delimiter (spreadsheet exports) ends the row, it adds no field.
  if (out->size() > 1 && out->back().empty()) out->pop_back();
}

bool ParseNumber(std::string_view f, double* v) {
  if (!f.empty() && f.front() == '+') f.remove_prefix(1);
  if (f.empty()) return false;
  auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), *v);
  return ec == std::errc() && p == f.data() + f.size();
}

bool AllNumbers(const std::vector<std::string_view>& fields) {
  double v;
  for (auto f : fields) if (!ParseNumber(f, &v)) return false;
  return true;
}

bool IsComment(std::string_view s) {
  const size_t i = s.find_first_not_of(" \t");
  return i != std::string_view::npos && s[i] == '#';
}

bool IsBlank(std::string_view s) { return s.find_first_not_of(" \t") == std::string_view::npos; }

// The --delimiter flag, or nullopt to detect.
std::optional<Delim> GivenDelim(const std::string& s) {
  if (s.empty()) return std::nullopt;
  const std::string l = Lower(s);
  if (l == "tab" || s == "\t" || s == "\\t") return Delim{'\t', false};
  if (l == "space" || l == "whitespace" || l == "ws" || s == " ") return Delim{' ', true};
  if (l == "comma") return Delim{',', false};
  if (l == "semicolon") return Delim{';', false};
  if (s.size() == 1 && s[0] != '#' && s[0] != '.' && !std::isdigit(static_cast<unsigned char>(s[0])) &&
      s[0] != '-' && s[0] != '+') {
    return Delim{s[0], false};
  }
  throw InputError("--delimiter '" + s.substr(0, 20) +
                   "' is not one of , ; tab space (or another single character that is not a digit, sign, '.' or '#')");
}

// 1-based positive integer, or 0.
int Position(const std::string& s) {
  if (s.empty() || s.size() > 6) return 0;
  for (char c : s) if (!std::isdigit(static_cast<unsigned char>(c))) return 0;
  return std::stoi(s);
}

double TimeScale(const std::string& unit) {
  if (unit.empty() || unit == "s") return 1.0;
  if (unit == "ms") return 1e-3;
  if (unit == "us") return 1e-6;
  throw InputError("--time-unit '" + unit.substr(0, 20) + "' is not one of s, ms, us");
}

// A line of a text log's preamble.
struct CsvPreLine { size_t no; std::string text; bool comment; };

// What the preamble of a text log says: its last non-blank line before the
// data (the header candidate) and the delimiter that splits the first data
// line (in *line, split into *fields) into numbers.
struct CsvPreamble {
  std::optional<CsvPreLine> last;
  std::optional<Delim> delim;
};

// Reads comment, blank and other lines up to the first data line.
CsvPreamble ReadPreamble(LineReader& reader, const std::string& path, const LogSelect& sel, std::string* line_ptr,
                         std::vector<std::string_view>* fields_ptr) {
  CsvPreamble result;
  CsvPreamble* out = &result;
  std::string& line = *line_ptr;
  std::vector<std::string_view>& fields = *fields_ptr;
  size_t skipped = 0;       // non-blank lines before it
  std::optional<Delim>& delim = out->delim;
  std::optional<CsvPreLine>& last = out->last;
  delim = GivenDelim(sel.delimiter);
  bool found = false;
  while (reader.Next(&line)) {
    if (reader.line_no() == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 BOM
    if (IsBlank(line)) continue;
    if (!IsComment(line)) {
      std::string_view sv = TrimView(line);
      const bool looks_numeric = !sv.empty() && (std::isdigit(static_cast<unsigned char>(sv[0])) ||
                                                 sv[0] == '-' || sv[0] == '+' || sv[0] == '.');
      if (delim) {
        Split(line, *delim, &fields);
        if (AllNumbers(fields)) { found = true; break; }
      } else {
        for (const Delim d : {Delim{';', false}, Delim{'\t', false}, Delim{',', false}, Delim{' ', true}}) {
          Split(line, d, &fields);
          if (fields.size() >= 2 && AllNumbers(fields)) { delim = d; break; }
        }
        if (delim) { found = true; break; }
        Split(line, Delim{' ', true}, &fields);
        if (looks_numeric && fields.size() == 1 && AllNumbers(fields)) {
          throw InputError(path + ": line " + std::to_string(reader.line_no()) + " " + Shown(line) +
                           " has a single number: a log needs an input and an output column");
        }
      }
      if (looks_numeric) {
        throw InputError(path + ": line " + std::to_string(reader.line_no()) + " " + Shown(line) +
                         " looks like data, but " +
                         (delim ? "the delimiter " + delim->Name() + " does not split it into numbers"
                                : std::string("no delimiter (; tab , whitespace) splits it into numbers")) +
                         " (decimal commas? a stray field?); pass --delimiter or repair the file");
      }
    }
    if (last) ++skipped;
    last = CsvPreLine{reader.line_no(), line, IsComment(line)};
    if (reader.line_no() > kMaxPreambleLines) {
      throw InputError(path + ": no numeric data row in the first " + std::to_string(kMaxPreambleLines) +
                       " lines (line " + std::to_string(reader.line_no()) + ": " + Shown(line) + "); not a text log?");
    }
  }
  if (!found) {
    if (!last) throw InputError(path + ": empty file (expected a header line such as t,torque,position and numeric rows)");
    throw InputError(path + ": no numeric data row (last line " + std::to_string(last->no) + ": " +
                     Shown(last->text) + ")" +
                     (sel.delimiter.empty() ? "" : "; is --delimiter " + sel.delimiter + " right?"));
  }
  return result;
}

// The column names (from the header: the last line before the data, comment
// mark stripped, when it has as many fields as the data) and the layout
// sentence that every message about the file quotes.
struct CsvHeader {
  std::vector<std::string> names;
  std::string layout;
};

CsvHeader ReadHeader(const std::optional<CsvPreLine>& last, const Delim& delim_value, size_t ncols,
                     size_t first_data, const std::string& path) {
  const std::optional<Delim> delim = delim_value;
  std::vector<std::string> names;
  size_t header_line = 0;
  bool header_comment = false;
  if (last) {
    std::string_view h = last->text;
    if (last->comment) {
      h.remove_prefix(h.find('#'));
      while (!h.empty() && h.front() == '#') h.remove_prefix(1);
    }
    std::vector<std::string_view> hf;
    Split(h, *delim, &hf);
    if (hf.size() == ncols && !AllNumbers(hf)) {
      for (auto f : hf) names.emplace_back(f);
      header_line = last->no;
      header_comment = last->comment;
    } else if (!last->comment) {
      throw InputError(path + ": the line before the data (line " + std::to_string(last->no) + ", " +
                       Shown(last->text) + ") has " + std::to_string(hf.size()) + " fields separated by " +
                       delim->Name() + ", the first data line " + std::to_string(first_data) + " has " +
                       std::to_string(ncols) + "; mark it with '#' if it is not a header, or pass --delimiter");
    }
  }
  std::string layout = "text, " + delim->Name() + "-separated, " + std::to_string(ncols) + " columns, ";
  std::string name_list;
  for (size_t i = 0; i < names.size() && i < 12; ++i) {
    name_list += (i ? ", " : "") + names[i].substr(0, 24);
  }
  if (names.size() > 12) name_list += ", ...";
  if (header_line) {
    layout += "header at line " + std::to_string(header_line) + (header_comment ? " (comment)" : "") + ": " + name_list;
  } else {
    layout += "no header (columns by position 1.." + std::to_string(ncols) + ")";
  }
  layout += ", data from line " + std::to_string(first_data);

  return {names, layout};
}

// The column that spec names (exact name, then a unique case-insensitive
// match, then a position from 1); -1 when absent and not required.
int FindColumn(const std::string& spec, bool required, const char* flag, const std::vector<std::string>& names,
               size_t ncols, const std::string& path, const std::string& layout) {
  if (!required && (spec.empty() || spec == "none")) return -1;
  for (size_t i = 0; i < names.size(); ++i) if (names[i] == spec) return static_cast<int>(i);
  int match = -1, count = 0;
  for (size_t i = 0; i < names.size(); ++i) {
    if (Lower(names[i]) == Lower(spec)) { match = static_cast<int>(i); ++count; }
  }
  if (count == 1) return match;
  const int pos = Position(spec);
  if (pos >= 1 && static_cast<size_t>(pos) <= ncols) return pos - 1;
  if (!required) return -1;
  std::string msg = path + ": no column '" + spec.substr(0, 40) + "' (" + layout + "); ";
  if (pos > 0) msg += "position " + std::to_string(pos) + " is past the last column; ";
  msg += std::string("choose with ") + flag + " NAME or a position 1.." + std::to_string(ncols);
  if (std::string(flag) == "--time-column") msg += ", or --time-column none with --rate";
  throw InputError(msg);
}

// The sample rate: --rate (with a warning when the time column disagrees),
// or the time column's (refused when implausible for a device log).
void ResolveRate(const std::string& path, const LogSelect& sel, const TimeChecker& times, int ct, size_t rows,
                 const std::string& time_col_name, LogInfo* out) {
  LogInfo& info = *out;
  const bool rate_given = sel.sample_rate_hz > 0.0;
  if (rate_given) {
    info.sample_rate_hz = sel.sample_rate_hz;
    if (ct >= 0 && rows >= 2) {
      const double T = 1.0 / sel.sample_rate_hz;
      const double jitter = std::max(std::abs(times.MaxInterval() - T), std::abs(times.MinInterval() - T));
      std::ostringstream os;
      os.precision(3);
      os << "--rate " << std::to_string(sel.sample_rate_hz).substr(0, 12) << " Hz used; the time column's intervals deviate from 1/rate by up to "
         << jitter << " s (" << 100.0 * jitter / T << " % of an interval)";
      const double tr = times.Rate();
      if (std::abs(tr - sel.sample_rate_hz) > 0.01 * sel.sample_rate_hz) {
        os << " and imply " << tr << " Hz on average: check --rate";
      }
      if (jitter > 1e-6 * T) info.warnings.push_back(os.str());
    }
  } else {
    info.sample_rate_hz = times.Rate();
    if (!(info.sample_rate_hz > 0.0) || !std::isfinite(info.sample_rate_hz)) {
      throw InputError(path + ": cannot tell the sample rate (fewer than 2 rows?); pass --rate");
    }
    if (sel.time_unit.empty() && (info.sample_rate_hz < 10.0 || info.sample_rate_hz > 1e6)) {
      std::ostringstream os;
      os.precision(4);
      os << path << ": the time " << time_col_name << " implies a sample rate of " << info.sample_rate_hz
         << " Hz (mean interval " << 1.0 / info.sample_rate_hz << " s), implausible for a device log: ";
      if (info.sample_rate_hz * 1e3 >= 10.0 && info.sample_rate_hz * 1e3 <= 1e6) {
        os << "is it in milliseconds? pass --time-unit ms (" << info.sample_rate_hz * 1e3 << " Hz)";
      } else if (info.sample_rate_hz * 1e6 >= 10.0 && info.sample_rate_hz * 1e6 <= 1e6) {
        os << "is it in microseconds? pass --time-unit us (" << info.sample_rate_hz * 1e6 << " Hz)";
      } else {
        os << "is it a sample index or another quantity? choose the time column with --time-column, or give --rate";
      }
      os << "; --time-unit s accepts it as is";
      throw InputError(os.str());
    }
  }
}

LogInfo StreamCsv(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open log file (does it exist?)");
  const double time_scale = TimeScale(sel.time_unit);
  LineReader reader(in, path);
  std::string line;
  std::vector<std::string_view> fields;
  const CsvPreamble pre = ReadPreamble(reader, path, sel, &line, &fields);
  const std::optional<Delim> delim = pre.delim;
  const size_t first_data = reader.line_no();
  const size_t ncols = fields.size();
  const std::vector<double> first_values = [&] {
    std::vector<double> v(ncols);
    for (size_t i = 0; i < ncols; ++i) ParseNumber(fields[i], &v[i]);
    return v;
  }();
  const CsvHeader header = ReadHeader(pre.last, *delim, ncols, first_data, path);
  const std::vector<std::string>& names = header.names;
  std::string layout = header.layout;
  auto find_col = [&](const std::string& spec, bool required, const char* flag) {
    return FindColumn(spec, required, flag, names, ncols, path, layout);
  };
  const int ci = find_col(sel.input_column, true, "--input-column");
  const int co = find_col(sel.output_column, true, "--output-column");
  const bool rate_given = sel.sample_rate_hz > 0.0;
  const int ct = sel.time_column == "none" ? -1 : find_col(sel.time_column, !rate_given, "--time-column");
  auto col_name = [&](int c) {
    return names.empty() ? "column " + std::to_string(c + 1) : "column '" + names[c].substr(0, 40) + "'";
  };
  layout += "; input " + col_name(ci) + ", output " + col_name(co) + ", time " + (ct >= 0 ? col_name(ct) : "none");

  TimeChecker times(path, sel.max_interval_deviation, !rate_given);
  ConstantCheck constant;
  std::vector<double> u, y;
  u.reserve(kChunk);
  y.reserve(kChunk);
  size_t rows = 0;
  auto flush = [&] {
    if (u.empty()) return;
    constant.Add(u.data(), u.size());
    sink(u.data(), y.data(), u.size());
    u.clear();
    y.clear();
  };
  bool first = true;
  do {
    size_t line_no = first ? first_data : reader.line_no();
    if (!first) {
      if (IsBlank(line) || IsComment(line)) continue;
      Split(line, *delim, &fields);
      if (fields.size() != ncols) {
        throw InputError(path + ": line " + std::to_string(line_no) + " has " + std::to_string(fields.size()) +
                         " fields separated by " + delim->Name() + ", the first data line " +
                         std::to_string(first_data) + " has " + std::to_string(ncols) +
                         " (truncated row? mixed delimiters?)");
      }
    }
    auto parse = [&](int col) {
      double v = 0.0;
      auto where = [&] { return "line " + std::to_string(line_no) + ", " + col_name(col); };
      if (first) v = first_values[col];
      else if (!ParseNumber(fields[col], &v)) {
        throw InputError(path + ": " + where() + ": " + Shown(fields[col]) + " is not a number");
      }
      if (!std::isfinite(v)) CheckFinite(v, path, where());
      return v;
    };
    const double uv = parse(ci), yv = parse(co);
    if (ct >= 0) times.AddLazy(parse(ct) * time_scale, [&] { return "line " + std::to_string(line_no); });
    u.push_back(uv * sel.input_scale);
    y.push_back(yv * sel.output_scale);
    ++rows;
    if (u.size() == kChunk) flush();
    first = false;
  } while (reader.Next(&line));
  flush();
  if (!constant.varies) {
    throw InputError(path + ": input " + col_name(ci) +
                     " is constant: the log has no excitation to identify from (wrong --input-column?)");
  }
  LogInfo info;
  info.source = path;
  info.num_samples = rows;
  info.layout = layout;
  ResolveRate(path, sel, times, ct, rows, ct >= 0 ? col_name(ct) : std::string(), &info);
  return info;
}


// ---- MATLAB .mat (v5 and v7.3, through libmatio) ---------------------------

struct MatCloser { void operator()(mat_t* m) const { if (m) Mat_Close(m); } };
struct VarFree { void operator()(matvar_t* v) const { if (v) Mat_VarFree(v); } };

std::string MatVariables(mat_t* mat) {
  Mat_Rewind(mat);
  std::string list;
  int n = 0;
  while (matvar_t* v = Mat_VarReadNextInfo(mat)) {
    if (n < 12) list += (n ? ", " : "") + std::string(v->name ? v->name : "?").substr(0, 24);
    ++n;
    Mat_VarFree(v);
  }
  if (n > 12) list += ", ...";
  return n ? list : "none";
}

// The variable "name" or the field "name.field" of a struct, as doubles.
// Returns false when it does not exist (and required is false).
bool ReadMatVector(mat_t* mat, const std::string& path, const std::string& spec, const char* flag,
                   std::vector<double>* out) {
  const size_t dot = spec.find('.');
  const std::string var = spec.substr(0, dot);
  std::unique_ptr<matvar_t, VarFree> info(Mat_VarReadInfo(mat, var.c_str()));
  if (!info) return false;
  std::unique_ptr<matvar_t, VarFree> whole(Mat_VarRead(mat, var.c_str()));
  if (!whole) throw InputError(path + ": variable '" + var.substr(0, 40) + "' cannot be read (corrupt file?)");
  matvar_t* v = whole.get();
  if (dot != std::string::npos) {
    if (v->class_type != MAT_C_STRUCT) {
      throw InputError(path + ": '" + var.substr(0, 40) + "' is not a struct; " + flag + " " + spec.substr(0, 40) +
                       " names a field of one");
    }
    v = Mat_VarGetStructFieldByName(v, spec.substr(dot + 1).c_str(), 0);
    if (!v) {
      std::string fields;
      const size_t nf = Mat_VarGetNumberOfFields(whole.get());
      char* const* names = Mat_VarGetStructFieldnames(whole.get());
      for (size_t i = 0; names && i < nf && i < 12; ++i) {
        if (i) fields += ", ";
        fields += std::string(names[i]).substr(0, 24);
      }
      throw InputError(path + ": struct '" + var.substr(0, 40) + "' has no field '" + spec.substr(dot + 1, 40) +
                       "' (fields: " + fields + "); choose one with " + flag);
    }
  }
  size_t n = 1;
  int long_dims = 0;
  for (int i = 0; i < v->rank; ++i) {
    n *= v->dims[i];
    if (v->dims[i] > 1) ++long_dims;
  }
  if (v->isComplex || long_dims > 1 || !v->data) {
    std::string shape;
    for (int i = 0; i < v->rank; ++i) {
      if (i) shape += 'x';
      shape += std::to_string(v->dims[i]);
    }
    throw InputError(path + ": '" + spec.substr(0, 40) + "' is " + (v->isComplex ? "complex " : "") + shape +
                     "; expected a real vector (one signal per variable; save columns as separate variables)");
  }
  out->resize(n);
  auto copy = [&](auto* p) { for (size_t i = 0; i < n; ++i) (*out)[i] = static_cast<double>(p[i]); };
  switch (v->class_type) {
    case MAT_C_DOUBLE: copy(static_cast<const double*>(v->data)); break;
    case MAT_C_SINGLE: copy(static_cast<const float*>(v->data)); break;
    case MAT_C_INT8: copy(static_cast<const int8_t*>(v->data)); break;
    case MAT_C_UINT8: copy(static_cast<const uint8_t*>(v->data)); break;
    case MAT_C_INT16: copy(static_cast<const int16_t*>(v->data)); break;
    case MAT_C_UINT16: copy(static_cast<const uint16_t*>(v->data)); break;
    case MAT_C_INT32: copy(static_cast<const int32_t*>(v->data)); break;
    case MAT_C_UINT32: copy(static_cast<const uint32_t*>(v->data)); break;
    case MAT_C_INT64: copy(static_cast<const int64_t*>(v->data)); break;
    case MAT_C_UINT64: copy(static_cast<const uint64_t*>(v->data)); break;
    default:
      throw InputError(path + ": '" + spec.substr(0, 40) + "' is not numeric (class " +
                       std::to_string(static_cast<int>(v->class_type)) + ")");
  }
  return true;
}

LogInfo StreamMatInProcess(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  Mat_LogInitFunc("zwidth", [](int, char*) {});  // no stderr chatter from libmatio
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(path + ": cannot open as a MATLAB .mat file (truncated or corrupt?)");
  const char* version = Mat_GetVersion(mat.get()) == MAT_FT_MAT73 ? "v7.3" : "v5";
  std::vector<double> u, y, t;
  auto need = [&](const std::string& spec, const char* flag, std::vector<double>* v) {
    if (!ReadMatVector(mat.get(), path, spec, flag, v)) {
      throw InputError(path + ": no variable '" + spec.substr(0, 40) + "' in this MATLAB " + version +
                       " file (variables: " + MatVariables(mat.get()) + "); choose one with " + flag);
    }
  };
  need(sel.input_column, "--input-column", &u);
  need(sel.output_column, "--output-column", &y);
  const bool rate_given = sel.sample_rate_hz > 0.0;
  bool have_time = false;
  if (sel.time_column != "none") {
    have_time = ReadMatVector(mat.get(), path, sel.time_column, "--time-column", &t);
    if (!have_time && !rate_given) {
      throw InputError(path + ": no time variable '" + sel.time_column.substr(0, 40) + "' (variables: " +
                       MatVariables(mat.get()) + "); choose one with --time-column, or pass --rate");
    }
  }
  if (u.size() != y.size() || (have_time && t.size() != u.size())) {
    throw InputError(path + ": the variables have different lengths (input " + std::to_string(u.size()) +
                     ", output " + std::to_string(y.size()) + (have_time ? ", time " + std::to_string(t.size()) : "") + ")");
  }
  if (u.empty()) throw InputError(path + ": variable '" + sel.input_column.substr(0, 40) + "' is empty");
  TimeChecker times(path, sel.max_interval_deviation, !rate_given);
  for (size_t i = 0; i < u.size(); ++i) {
    const std::string where = "sample " + std::to_string(i + 1);
    CheckFinite(u[i], path + ":" + sel.input_column, where);
    CheckFinite(y[i], path + ":" + sel.output_column, where);
    if (have_time) {
      CheckFinite(t[i], path + ":" + sel.time_column, where);
      times.Add(t[i], where + " of " + sel.time_column);
    }
  }
  ConstantCheck constant;
  constant.Add(u.data(), u.size());
  if (!constant.varies) {
    throw InputError(path + ": input '" + sel.input_column.substr(0, 40) + "' is constant: no excitation to identify from");
  }
  for (size_t off = 0; off < u.size(); off += kChunk) sink(u.data() + off, y.data() + off, std::min(kChunk, u.size() - off));
  LogInfo info;
  info.source = path;
  info.num_samples = u.size();
  info.sample_rate_hz = rate_given ? sel.sample_rate_hz : times.Rate();
  if (!(info.sample_rate_hz > 0.0) || !std::isfinite(info.sample_rate_hz)) {
    throw InputError(path + ": cannot tell the sample rate (fewer than 2 samples?); pass --rate");
  }
  return info;
}

// A binary log parsed in a child process (io/isolated.h): `parse` runs there and its
// chunks come back framed 'c' u[n] y[n], then 'i' count rate. `what` names the
// format in errors.
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

LogInfo StreamMat(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  LogInfo info = StreamIsolatedLog(path, ".mat file", sel, sink, StreamMatInProcess);
  info.layout = "MATLAB .mat (libmatio)";
  return info;
}

std::string H5Where(const std::string& path, const std::string& ds) { return path + ":" + ds; }

H5::DataSet OpenDataset(H5::H5File& file, const std::string& path, const std::string& name,
                        const char* flag) {
  if (!internal::H5LinkExists(file.getId(), path, name)) {
    throw InputError(path + ": no dataset '" + name + "'; choose one with " + flag);
  }
  H5::DataSet ds;
  try {
    ds = file.openDataSet(name);
  } catch (const H5::Exception&) {
    throw InputError(path + ": '" + name + "' is not a readable dataset");
  }
  internal::CheckH5DatasetLocal(ds.getId(), H5Where(path, name));
  const H5T_class_t cls = ds.getTypeClass();
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
    throw InputError(H5Where(path, name) + ": not a numeric dataset (HDF5 type class " + std::to_string(cls) +
                     "); expected floating-point or integer samples");
  }
  return ds;
}

size_t Length1D(const H5::DataSet& ds, const std::string& where) {
  H5::DataSpace sp = ds.getSpace();
  const int rank = sp.getSimpleExtentNdims();
  std::vector<hsize_t> dims(std::max(rank, 1));
  sp.getSimpleExtentDims(dims.data());
  hsize_t n = 0;
  if (rank == 1) n = dims[0];
  else if (rank == 2 && (dims[0] == 1 || dims[1] == 1)) n = dims[0] * dims[1];
  else throw InputError(where + ": expected a 1-D dataset, found rank " + std::to_string(rank));
  if (n > kMaxLogSamples) {
    throw InputError(where + ": declares " + std::to_string(n) + " samples, more than zwidth reads (" +
                     std::to_string(kMaxLogSamples) + "); split the log");
  }
  return n;
}

void ReadSlab(const H5::DataSet& ds, hsize_t offset, hsize_t count, double* out,
              const std::string& where) {
  H5::DataSpace file_space = ds.getSpace();
  const int rank = file_space.getSimpleExtentNdims();
  std::vector<hsize_t> dims(rank);
  file_space.getSimpleExtentDims(dims.data());
  std::vector<hsize_t> off(rank, 0), cnt(rank, 1);
  const int axis = (rank == 2 && dims[0] == 1) ? 1 : 0;
  off[axis] = offset;
  cnt[axis] = count;
  file_space.selectHyperslab(H5S_SELECT_SET, cnt.data(), off.data());
  H5::DataSpace mem_space(1, &count);
  try {
    ds.read(out, H5::PredType::NATIVE_DOUBLE, mem_space, file_space);
  } catch (const H5::Exception&) {
    throw InputError(where + ": cannot read (truncated or corrupt file?)");
  }
}

// A logger that preallocates its datasets and stops early leaves parts never
// written, which read back as fill values: a 70 kB file can declare 1e10
// samples. Refused here, before streaming: every chunk of a chunked dataset
// must be allocated, and all of a contiguous one.
void CheckWritten(const H5::DataSet& ds, const std::string& where) {
  const H5::DSetCreatPropList plist = ds.getCreatePlist();
  H5::DataSpace sp = ds.getSpace();
  const int rank = sp.getSimpleExtentNdims();
  std::vector<hsize_t> dims(std::max(rank, 1), 1);
  sp.getSimpleExtentDims(dims.data());
  hsize_t elements = 1;
  for (int i = 0; i < rank; ++i) elements *= dims[i];
  if (plist.getLayout() == H5D_CHUNKED) {
    std::vector<hsize_t> chunk(std::max(rank, 1), 1);
    plist.getChunk(rank, chunk.data());
    hsize_t expected = 1, allocated = 0;
    for (int i = 0; i < rank; ++i) expected *= (dims[i] + chunk[i] - 1) / std::max<hsize_t>(chunk[i], 1);
    if (H5Dget_num_chunks(ds.getId(), sp.getId(), &allocated) < 0) return;  // cannot tell: the reads decide
    if (allocated < expected) {
      throw InputError(where + ": declares " + std::to_string(elements) + " samples, but only " +
                       std::to_string(allocated) + " of its " + std::to_string(expected) +
                       " chunks were ever written (a log preallocated and not filled?)");
    }
  } else if (plist.getLayout() == H5D_CONTIGUOUS && plist.getNfilters() == 0) {
    if (ds.getStorageSize() < elements * ds.getDataType().getSize()) {
      throw InputError(where + ": declares " + std::to_string(elements) + " samples, but its data were never written");
    }
  }
}

}  // namespace

namespace internal {

herr_t DenyExternalLink(const char*, const char*, const char*, const char*, unsigned*, hid_t, void*) {
  return -1;  // an external link would read another file: never followed
}

H5::FileAccPropList SafeH5Access() {
  H5::FileAccPropList fapl;
  H5Pset_elink_cb(fapl.getId(), DenyExternalLink, nullptr);
  return fapl;
}

bool H5LinkExists(hid_t file, const std::string& path, const std::string& name) {
  // Component by component from the root: H5Lexists on "/a/b" would follow a
  // link "/a" into another file; H5Lget_info on each prefix does not.
  if (name.empty() || name[0] != '/') return false;
  std::string prefix;
  size_t start = 1;
  while (start <= name.size()) {
    size_t slash = name.find('/', start);
    if (slash == std::string::npos) slash = name.size();
    if (slash == start) { start = slash + 1; continue; }
    prefix = name.substr(0, slash);
    if (H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    H5L_info_t info;
    if (H5Lget_info(file, prefix.c_str(), &info, H5P_DEFAULT) < 0) return false;
    if (info.type == H5L_TYPE_EXTERNAL || info.type >= H5L_TYPE_UD_MIN) {
      throw InputError(path + ":" + prefix + ": is an external link (to another file); zwidth reads only "
                       "what is inside the file: copy the data into it");
    }
    start = slash + 1;
  }
  return true;
}

bool IsPlainNumber(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  if (cls == H5T_FLOAT) {
    // Only the IEEE single and double layouts: a corrupt file can declare any
    // (mantissa, exponent) split, whose soft conversion libhdf5 does slowly and
    // with buffers sized by that declaration.
    for (hid_t std_type : {H5T_IEEE_F32LE, H5T_IEEE_F32BE, H5T_IEEE_F64LE, H5T_IEEE_F64BE}) {
      if (H5Tequal(type, std_type) > 0) return true;
    }
    return false;
  }
  if (cls == H5T_INTEGER) {
    const size_t size = H5Tget_size(type);
    return (size == 1 || size == 2 || size == 4 || size == 8) && H5Tget_precision(type) == 8 * size &&
           H5Tget_offset(type) == 0;
  }
  return false;
}

void CheckH5DatasetLocal(hid_t dataset, const std::string& where) {
  const hid_t type = H5Dget_type(dataset);
  const bool plain = type >= 0 && IsPlainNumber(type);
  if (type >= 0) H5Tclose(type);
  if (!plain) {
    throw InputError(where + ": not stored as plain numbers (expected IEEE float32/float64 or 8- to 64-bit "
                     "integers)");
  }
  const hid_t dcpl = H5Dget_create_plist(dataset);
  if (dcpl < 0) throw InputError(where + ": unreadable dataset properties (corrupt file?)");
  const int external = H5Pget_external_count(dcpl);
  const H5D_layout_t layout = H5Pget_layout(dcpl);
  H5Pclose(dcpl);
  if (external != 0) {
    throw InputError(where + ": its data are stored in external files; zwidth reads only what is "
                     "inside the file: copy the data into it");
  }
  if (layout == H5D_VIRTUAL) {
    throw InputError(where + ": a virtual dataset (data from other files); copy the data into the file");
  }
}

double ReadH5ScalarAttribute(hid_t object, const std::string& name, const std::string& where) {
  const hid_t a = H5Aopen(object, name.c_str(), H5P_DEFAULT);
  if (a < 0) throw InputError(where + ": attribute " + name + " is unreadable (corrupt file?)");
  const hid_t space = H5Aget_space(a);
  const hid_t type = H5Aget_type(a);
  const hssize_t points = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  double v = 0.0;
  herr_t read = -1;
  const bool plain = type >= 0 && IsPlainNumber(type);
  if (points == 1 && plain) read = H5Aread(a, H5T_NATIVE_DOUBLE, &v);
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  if (points != 1) {
    throw InputError(where + ": attribute " + name + " has " + std::to_string(points) +
                     " values; it must be one number (a scalar)");
  }
  if (!plain) {
    throw InputError(where + ": attribute " + name + " is not a number; it must be one number (a scalar)");
  }
  if (read < 0) throw InputError(where + ": attribute " + name + " is unreadable (corrupt file?)");
  return v;
}

LogInfo StreamHdf5InProcess(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  H5::Exception::dontPrint();
  std::unique_ptr<H5::H5File> file;
  try {
    if (!H5::H5File::isHdf5(path)) throw InputError(path + ": not an HDF5 file");
    file = std::make_unique<H5::H5File>(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, SafeH5Access());
  } catch (const H5::Exception&) {
    throw InputError(path + ": cannot open as HDF5 (missing, truncated or corrupt file)");
  }
  try {
    H5::DataSet du = OpenDataset(*file, path, sel.input_dataset, "--input-dataset");
    H5::DataSet dy = OpenDataset(*file, path, sel.output_dataset, "--output-dataset");
    const size_t n = Length1D(du, H5Where(path, sel.input_dataset));
    if (Length1D(dy, H5Where(path, sel.output_dataset)) != n) {
      throw InputError(path + ": '" + sel.input_dataset + "' and '" + sel.output_dataset +
                       "' have different lengths");
    }
    if (n == 0) throw InputError(path + ": dataset '" + sel.input_dataset + "' is empty");
    CheckWritten(du, H5Where(path, sel.input_dataset));
    CheckWritten(dy, H5Where(path, sel.output_dataset));
    double attr_rate = 0.0;
    if (file->attrExists("sample_rate_hz")) {
      attr_rate = ReadH5ScalarAttribute(file->getId(), "sample_rate_hz", path);
      if (!(attr_rate > 0.0) || !std::isfinite(attr_rate)) {
        throw InputError(path + ": attribute sample_rate_hz = " + std::to_string(attr_rate) +
                         " must be finite and > 0");
      }
    }
    const bool have_time = H5LinkExists(file->getId(), path, sel.time_dataset);
    H5::DataSet dt;
    if (have_time) {
      dt = OpenDataset(*file, path, sel.time_dataset, "--time-dataset");
      if (Length1D(dt, H5Where(path, sel.time_dataset)) != n) {
        throw InputError(path + ": '" + sel.time_dataset + "' has a different length from the signals");
      }
      CheckWritten(dt, H5Where(path, sel.time_dataset));
    } else if (attr_rate <= 0.0 && sel.sample_rate_hz <= 0.0) {
      throw InputError(path + ": neither a '" + sel.time_dataset +
                       "' dataset nor a sample_rate_hz attribute; pass --rate");
    }
    TimeChecker times(path, sel.max_interval_deviation, sel.sample_rate_hz <= 0.0);  // --rate: only increasing
    ConstantCheck constant;
    std::vector<double> u(kChunk), y(kChunk), t(kChunk);
    for (size_t off = 0; off < n; off += kChunk) {
      const size_t cnt = std::min(kChunk, n - off);
      ReadSlab(du, off, cnt, u.data(), H5Where(path, sel.input_dataset));
      ReadSlab(dy, off, cnt, y.data(), H5Where(path, sel.output_dataset));
      if (have_time) ReadSlab(dt, off, cnt, t.data(), H5Where(path, sel.time_dataset));
      for (size_t i = 0; i < cnt; ++i) {
        const std::string where = "sample " + std::to_string(off + i);
        CheckFinite(u[i], H5Where(path, sel.input_dataset), where);
        CheckFinite(y[i], H5Where(path, sel.output_dataset), where);
        if (have_time) {
          CheckFinite(t[i], H5Where(path, sel.time_dataset), where);
          times.Add(t[i], where + " of " + sel.time_dataset);
        }
      }
      constant.Add(u.data(), cnt);
      sink(u.data(), y.data(), cnt);
    }
    if (!constant.varies) {
      throw InputError(path + ": input dataset '" + sel.input_dataset +
                       "' is constant: the log has no excitation to identify from");
    }
    LogInfo info;
    info.source = path;
    info.num_samples = n;
    const double time_rate = have_time ? times.Rate() : 0.0;
    if (sel.sample_rate_hz > 0.0) info.sample_rate_hz = sel.sample_rate_hz;
    else if (attr_rate > 0.0) {
      if (time_rate > 0.0 && std::abs(time_rate - attr_rate) > 0.01 * attr_rate) {
        throw InputError(path + ": attribute sample_rate_hz = " + std::to_string(attr_rate) +
                         " disagrees with the time stamps (" + std::to_string(time_rate) + " Hz)");
      }
      info.sample_rate_hz = attr_rate;
    } else {
      info.sample_rate_hz = time_rate;
    }
    if (!(info.sample_rate_hz > 0.0)) throw InputError(path + ": cannot tell the sample rate; pass --rate");
    return info;
  } catch (const H5::Exception& e) {
    throw InputError(path + ": HDF5 error (" + e.getDetailMsg() + "): truncated or corrupt file?");
  }
}

}  // namespace internal

namespace {

// The file is read in a child process (io/isolated.h) that streams the chunks
// through a pipe: a crash in libhdf5 becomes an InputError here, and the data
// is still read once, in bounded memory. Frames: 'c' then u[n], y[n] (a chunk);
// 'i' then the sample count (uint64) and the rate (the end).
LogInfo StreamHdf5(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  return StreamIsolatedLog(path, "HDF5 file", sel, sink, internal::StreamHdf5InProcess);
}

void WriteCsvLog(const std::string& tmp, double rate, const std::vector<double>& u,
                 const std::vector<double>& y) {
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError("cannot create '" + tmp + "'");
  std::fputs("t,torque,position\n", f);
  for (size_t k = 0; k < u.size(); ++k) {
    std::fprintf(f, "%.17g,%.17g,%.17g\n", static_cast<double>(k) / rate, u[k], y[k]);
  }
  const bool ok = std::ferror(f) == 0;
  if (std::fclose(f) != 0 || !ok) throw InputError("failed writing '" + tmp + "' (disk full?)");
}

void WriteStringAttr(H5::H5Object& obj, const std::string& name, const std::string& value) {
  H5::StrType st(H5::PredType::C_S1, value.size() + 1);
  H5::Attribute a = obj.createAttribute(name, st, H5::DataSpace(H5S_SCALAR));
  a.write(st, value.c_str());
  a.close();
}

void WriteHdf5Log(const std::string& tmp, double rate, const std::vector<double>& u,
                  const std::vector<double>& y) {
  H5::Exception::dontPrint();
  try {
    H5::H5File file(tmp, H5F_ACC_TRUNC);
    const hsize_t n = u.size();
    H5::DataSpace space(1, &n);
    std::vector<double> t(n);
    for (hsize_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) / rate;
    auto write = [&](H5::Group& parent, const std::string& name, const std::vector<double>& v,
                     const std::string& unit) {
      H5::DataSet ds = parent.createDataSet(name, H5::PredType::IEEE_F64LE, space);
      ds.write(v.data(), H5::PredType::NATIVE_DOUBLE);
      WriteStringAttr(ds, "units", unit);
      ds.close();
    };
    H5::Group root = file.openGroup("/");
    write(root, "time", t, "s");
    H5::Group gi = file.createGroup("/input");
    H5::Group go = file.createGroup("/output");
    write(gi, "torque", u, "N m");
    write(go, "position", y, "rad");
    internal::WriteDoubleAttr(root, "sample_rate_hz", rate);
    WriteStringAttr(root, "sample_rate_units", "Hz");
    // Closed here, inside the try: an error at flush or close (a full disk)
    // must fail the write, not vanish in a destructor.
    gi.close();
    go.close();
    root.close();
    file.flush(H5F_SCOPE_GLOBAL);
    file.close();
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
}

}  // namespace

static bool HasExtension(const std::string& path, std::initializer_list<const char*> exts) {
  const std::string p = Lower(path);
  for (const char* s : exts) {
    const size_t n = std::strlen(s);
    if (p.size() >= n && p.compare(p.size() - n, n, s) == 0) return true;
  }
  return false;
}

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

LogInfo StreamLog(const std::string& path, const LogSelect& select, const LogSink& sink) {
  if (select.sample_rate_hz < 0.0 || !std::isfinite(select.sample_rate_hz)) {
    throw InputError("--rate must be finite and > 0");
  }
  for (const auto& [v, flag] : {std::pair{select.input_scale, "--input-scale"}, std::pair{select.output_scale, "--output-scale"}}) {
    if (!std::isfinite(v) || v == 0.0) {
      throw InputError(std::string(flag) + " = " + std::to_string(v) + ": must be finite and non-zero");
    }
  }
  TimeScale(select.time_unit);  // validates the flag
  CheckInputFile(path, "log");
  size_t total = 0;
  const LogSink capped = [&](const double* u, const double* y, size_t n) {
    total += n;
    if (total > kMaxLogSamples) {
      throw InputError(path + ": more than " + std::to_string(kMaxLogSamples) +
                       " samples, more than zwidth reads; split the log");
    }
    sink(u, y, n);
  };
  const LogFormat format = DetectLogFormat(path);
  if (format == LogFormat::kCsv) return StreamCsv(path, select, capped);
  if (!select.time_unit.empty() && select.time_unit != "s") {
    throw InputError(path + ": --time-unit applies to text logs; this " +
                     std::string(format == LogFormat::kMat ? "MATLAB" : "HDF5") +
                     " log's time is read in s (give --rate instead)");
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
  return info;
}

Log ReadLog(const std::string& path, const LogSelect& select) {
  Log log;
  log.info = StreamLog(path, select, [&](const double* u, const double* y, size_t n) {
    log.input.insert(log.input.end(), u, u + n);
    log.output.insert(log.output.end(), y, y + n);
  });
  return log;
}

void WriteLog(const std::string& path, double rate, const std::vector<double>& u,
              const std::vector<double>& y) {
  if (!(rate > 0.0)) throw InputError("sample rate must be > 0");
  // By extension: the file is about to be (re)written.
  const bool h5 = HasExtension(path, {".h5", ".hdf5", ".he5"});
  WriteAtomically(path, [&](const std::string& tmp) {
    if (h5) WriteHdf5Log(tmp, rate, u, y);
    else WriteCsvLog(tmp, rate, u, y);
  });
}

}  // namespace zwidth::io
