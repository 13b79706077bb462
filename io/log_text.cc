#include "io/log.h"

#include <algorithm>
#include <cerrno>
#include <cctype>
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
#include <tuple>

#include <sys/stat.h>

#include "io/atomic_file.h"
#include "io/io_internal.h"
#include "io/log_internal.h"
#include "io/log_units.h"
#include "model/error.h"


namespace zwidth::io::internal {
namespace {

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
  bool decimal_comma = false;  // numbers read "0,25" (LogSelect::decimal_comma or detected)
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

// A number as the file writes them (decimal point, or comma with d.decimal_comma).
bool ParseNumberIn(std::string_view f, const Delim& d, double* v) {
  return d.decimal_comma ? internal::ParseDecimalComma(f, v) : ParseNumber(f, v);
}

bool AllNumbers(const std::vector<std::string_view>& fields, const Delim& d = {}) {
  double v;
  for (auto f : fields) if (!ParseNumberIn(f, d, &v)) return false;
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
  throw InputError("LogSelect::delimiter '" + s.substr(0, 20) +
                   "' is not one of , ; tab space (or another single character that is not a digit, sign, '.' or '#')");
}

// 1-based positive integer, or 0.
int Position(const std::string& s) {
  if (s.empty() || s.size() > 6) return 0;
  for (char c : s) if (!std::isdigit(static_cast<unsigned char>(c))) return 0;
  return std::stoi(s);
}

}  // namespace

double TimeScale(const std::string& unit) {
  if (unit.empty() || unit == "s") return 1.0;
  if (unit == "ms") return 1e-3;
  if (unit == "us") return 1e-6;
  throw InputError("LogSelect::time_unit '" + unit.substr(0, 20) + "' is not one of s, ms, us");
}

namespace {

// A line of a text log's preamble.
struct CsvPreLine { size_t no; std::string text; bool comment; };

// What the preamble of a text log says: its last non-blank line before the
// data (the header candidate) and the delimiter that splits the first data
// line (in *line, split into *fields) into numbers.
struct CsvPreamble {
  std::optional<CsvPreLine> last;
  std::optional<CsvPreLine> before_last;  // the non-blank line before `last` (a header above a units row)
  std::optional<Delim> delim;
};

// The delimiters tried on the first data line, in order: with a decimal point
// (';', tab, ',', whitespace), then with a decimal comma (';', tab,
// whitespace); only the latter with LogSelect::decimal_comma.
std::vector<Delim> CandidateDelims(bool decimal_comma) {
  std::vector<Delim> out;
  if (!decimal_comma) out = {Delim{';', false}, Delim{'\t', false}, Delim{',', false}, Delim{' ', true}};
  for (const Delim d : {Delim{';', false, true}, Delim{'\t', false, true}, Delim{' ', true, true}}) out.push_back(d);
  return out;
}

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
  if (delim && sel.decimal_comma) {
    if (delim->c == ',' && !delim->ws) throw InputError("LogSelect::decimal_comma with LogSelect::delimiter ',': a comma cannot be both");
    delim->decimal_comma = true;
  }
  bool found = false;
  while (reader.Next(&line)) {
    if (reader.line_no() == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 BOM
    if (IsBlank(line)) continue;
    if (!IsComment(line)) {
      std::string_view sv = TrimView(line);
      if (!last && !sv.empty() && (sv[0] == '{' || sv[0] == '[')) {
        throw InputError(path + ": line " + std::to_string(reader.line_no()) + " " + Shown(line) +
                         ": this looks like a JSON file (a model or a scene), not a log; a model is what "
                         "boundary, check, relay, compare and export take (fit makes one from a log)");
      }
      const bool looks_numeric = !sv.empty() && (std::isdigit(static_cast<unsigned char>(sv[0])) ||
                                                 sv[0] == '-' || sv[0] == '+' || sv[0] == '.');
      if (delim) {
        Split(line, *delim, &fields);
        if (AllNumbers(fields, *delim)) { found = true; break; }
      } else {
        for (const Delim d : CandidateDelims(sel.decimal_comma)) {
          Split(line, d, &fields);
          if (fields.size() >= 2 && AllNumbers(fields, d)) { delim = d; break; }
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
                         " (decimal commas? a stray field?); pass LogSelect::delimiter or repair the file");
      }
    }
    if (last) ++skipped;
    out->before_last = last;
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
                     (sel.delimiter.empty() ? "" : "; is LogSelect::delimiter " + sel.delimiter + " right?"));
  }
  return result;
}

// The column names (from the header: the last line before the data, comment
// mark stripped, when it has as many fields as the data) and the layout
// sentence that every message about the file quotes.
struct CsvHeader {
  std::vector<std::string> names;
  std::vector<std::string> units;  // from a units row under the header ("" per column without), else empty
  std::string layout;
};

// The text of a preamble line, without a leading comment mark.
std::string_view PreLineText(const CsvPreLine& l) {
  std::string_view h = l.text;
  if (l.comment) {
    h.remove_prefix(h.find('#'));
    while (!h.empty() && h.front() == '#') h.remove_prefix(1);
  }
  return h;
}

// A units row: the line before the data holds a unit (or nothing) in every
// field and the line above it is a header with as many fields
// ("t;torque;position" over "s;mN m;deg"). Its fields, else nullopt.
std::optional<std::vector<std::string>> UnitsRow(const CsvPreamble& pre, const Delim& d, size_t ncols) {
  if (!pre.last || !pre.before_last) return std::nullopt;
  std::vector<std::string_view> f, h;
  Split(PreLineText(*pre.last), d, &f);
  Split(PreLineText(*pre.before_last), d, &h);
  if (f.size() != ncols || h.size() != ncols || AllNumbers(h, d)) return std::nullopt;
  bool any = false;
  for (std::string_view x : f) {
    if (x.empty()) continue;
    if (!internal::LooksLikeUnit(std::string(x))) return std::nullopt;
    any = true;
  }
  if (!any) return std::nullopt;
  return std::vector<std::string>(f.begin(), f.end());
}

CsvHeader ReadHeader(const std::optional<CsvPreLine>& last, const Delim& delim_value, size_t ncols,
                     size_t first_data, const std::string& path) {
  const std::optional<Delim> delim = delim_value;
  std::vector<std::string> names;
  size_t header_line = 0;
  bool header_comment = false;
  if (last) {
    const std::string_view h = PreLineText(*last);
    std::vector<std::string_view> hf;
    Split(h, *delim, &hf);
    if (hf.size() == ncols && !AllNumbers(hf, *delim)) {
      for (auto f : hf) names.emplace_back(f);
      header_line = last->no;
      header_comment = last->comment;
    } else if (!last->comment) {
      throw InputError(path + ": the line before the data (line " + std::to_string(last->no) + ", " +
                       Shown(last->text) + ") has " + std::to_string(hf.size()) + " fields separated by " +
                       delim->Name() + ", the first data line " + std::to_string(first_data) + " has " +
                       std::to_string(ncols) + "; mark it with '#' if it is not a header, or pass LogSelect::delimiter");
    }
  }
  std::string layout = "text, " + delim->Name() + "-separated" + (delim->decimal_comma ? " (decimal comma)" : "") +
                       ", " + std::to_string(ncols) + " columns, ";
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

  return {names, {}, layout};
}

// The column that spec names (exact name, then a unique case-insensitive
// match, then a position from 1); -1 when absent and not required.
int FindColumn(const std::string& spec, bool required, const char* flag, const std::vector<std::string>& names,
               size_t ncols, const std::string& path, const std::string& layout) {
  if (!required && (spec.empty() || spec == "none")) return -1;
  // Each rule in turn; a name that two columns answer is refused (reading
  // either one silently could fit the wrong signal).
  auto unique = [&](auto&& same, const char* how) {
    std::vector<size_t> hits;
    for (size_t i = 0; i < names.size(); ++i) if (same(names[i])) hits.push_back(i);
    if (hits.size() > 1) {
      throw InputError(path + ": " + std::to_string(hits.size()) + " columns answer to '" + spec.substr(0, 40) + "'" +
                       how + " (columns " + std::to_string(hits[0] + 1) + " and " + std::to_string(hits[1] + 1) +
                       "; " + layout + "): choose one by position with " + flag + " N");
    }
    return hits.empty() ? -1 : static_cast<int>(hits[0]);
  };
  // A header's unit in brackets ("torque [mNm]", "t (s)") is not part of the
  // name a default such as 'torque' or 't' looks for.
  auto without_unit = [](const std::string& n) {
    std::string base;
    internal::SplitBracketedUnit(n, &base, nullptr);
    return base;
  };
  if (const int c = unique([&](const std::string& n) { return n == spec; }, ""); c >= 0) return c;
  const std::string want = Lower(spec);
  if (const int c = unique([&](const std::string& n) { return Lower(n) == want; }, " (ignoring case)"); c >= 0) return c;
  if (const int c = unique([&](const std::string& n) { return Lower(without_unit(n)) == want; },
                           " (its unit in brackets aside)");
      c >= 0) {
    return c;
  }
  const int pos = Position(spec);
  if (pos >= 1 && static_cast<size_t>(pos) <= ncols) return pos - 1;
  if (!required) return -1;
  std::string msg = path + ": no column '" + spec.substr(0, 40) + "' (" + layout + "); ";
  if (pos > 0) msg += "position " + std::to_string(pos) + " is past the last column; ";
  msg += std::string("choose with ") + flag + " NAME or a position 1.." + std::to_string(ncols);
  if (std::string(flag) == "LogSelect::time_column") msg += ", or LogSelect::time_column none with LogSelect::sample_rate_hz";
  throw InputError(msg);
}

// "ms" or "us" when a time column's name carries that unit as a word of its
// own (t_ms, time_ms, "t [ms]", "time (us)", tUs is not split), else "".
std::string UnitInName(const std::string& name) {
  std::string word;
  std::vector<std::string> words;
  for (size_t i = 0; i <= name.size(); ++i) {
    const unsigned char c = i < name.size() ? static_cast<unsigned char>(name[i]) : ' ';
    if (std::isalnum(c) || c >= 0x80) {
      word += static_cast<char>(std::tolower(c));
    } else if (!word.empty()) {
      words.push_back(word);
      word.clear();
    }
  }
  for (const std::string& w : words) {
    if (w == "ms" || w == "msec" || w == "millisec" || w == "millisecond" || w == "milliseconds") return "ms";
    if (w == "us" || w == "usec" || w == "microsec" || w == "microsecond" || w == "microseconds" ||
        w == "\xc2\xb5s" || w == "\xce\xbcs") {  // micro sign or Greek mu, then s
      return "us";
    }
  }
  return "";
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
      const double T = info.period_s();
      const double jitter = std::max(std::abs(times.MaxInterval() - T), std::abs(times.MinInterval() - T));
      std::ostringstream os;
      os.precision(3);
      os << "LogSelect::sample_rate_hz " << std::to_string(sel.sample_rate_hz).substr(0, 12) << " Hz used; the time column's intervals deviate from 1/rate by up to "
         << jitter << " s (" << 100.0 * jitter / T << " % of an interval)";
      const double tr = times.Rate();
      if (std::abs(tr - sel.sample_rate_hz) > 0.01 * sel.sample_rate_hz) {
        os << " and imply " << tr << " Hz on average: check LogSelect::sample_rate_hz";
      }
      if (jitter > 1e-6 * T) info.warnings.push_back(os.str());
    }
  } else {
    info.sample_rate_hz = times.Rate();
    if (!(info.sample_rate_hz > 0.0) || !std::isfinite(info.sample_rate_hz)) {
      throw InputError(path + ": cannot tell the sample rate (fewer than 2 rows?); pass LogSelect::sample_rate_hz");
    }
    // 10 Hz itself is refused: a 10 kHz loop logged in ms reads as exactly that.
    if (sel.time_unit.empty() && !IsDeviceLogRate(info.sample_rate_hz)) {
      std::ostringstream os;
      os.precision(4);
      os << path << ": the time " << time_col_name << " implies a sample rate of " << info.sample_rate_hz
         << " Hz (mean interval " << info.period_s() << " s), implausible for a device log: ";
      if (info.sample_rate_hz * 1e3 >= 10.0 && info.sample_rate_hz * 1e3 <= 1e6) {
        os << "is it in milliseconds? pass LogSelect::time_unit ms (" << info.sample_rate_hz * 1e3 << " Hz)";
      } else if (info.sample_rate_hz * 1e6 >= 10.0 && info.sample_rate_hz * 1e6 <= 1e6) {
        os << "is it in microseconds? pass LogSelect::time_unit us (" << info.sample_rate_hz * 1e6 << " Hz)";
      } else {
        os << "is it a sample index or another quantity? choose the time column with LogSelect::time_column, or give LogSelect::sample_rate_hz";
      }
      os << "; LogSelect::time_unit s accepts it as is";
      throw InputError(os.str());
    }
    if (sel.time_unit.empty() && info.sample_rate_hz < 100.0) {
      std::ostringstream os;
      os.precision(4);
      os << "the time " << time_col_name << " implies " << info.sample_rate_hz
         << " Hz, low for a haptic device log: if it is in milliseconds pass LogSelect::time_unit ms ("
         << info.sample_rate_hz * 1e3 << " Hz); LogSelect::time_unit s silences this";
      info.warnings.push_back(os.str());
    }
  }
}

}  // namespace

// The input, output and time columns of a CSV log (time -1: none), how
// messages name them, and the layout line that says what was read.
struct CsvColumns {
  int input = -1, output = -1, time = -1;
  std::vector<std::string> names;  // the header's, empty without one
  std::string layout;
  std::string Name(int c) const {
    return names.empty() ? "column " + std::to_string(c + 1) : "column '" + names[c].substr(0, 40) + "'";
  }
};

CsvColumns SelectColumns(const LogSelect& sel, const CsvHeader& header, size_t ncols, const std::string& path) {
  CsvColumns c;
  c.names = header.names;
  c.layout = header.layout;
  auto find_col = [&](const std::string& spec, bool required, const char* flag) {
    return FindColumn(spec, required, flag, c.names, ncols, path, c.layout);
  };
  // The default input is 'torque', or on a linear axis 'force' (what
  // `zwidth simulate` writes for a linear model: "force [N]").
  const bool default_input = sel.input_column == LogSelect{}.input_column;
  c.input = default_input ? find_col(sel.input_column, false, "LogSelect::input_column") : -1;
  if (c.input < 0 && default_input) c.input = find_col("force", false, "LogSelect::input_column");
  if (c.input < 0) c.input = find_col(sel.input_column, true, "LogSelect::input_column");
  c.output = find_col(sel.output_column, true, "LogSelect::output_column");
  const bool rate_given = sel.sample_rate_hz > 0.0;
  c.time = sel.time_column == "none" ? -1 : find_col(sel.time_column, !rate_given, "LogSelect::time_column");
  c.layout += "; input " + c.Name(c.input) + ", output " + c.Name(c.output) + ", time " +
              (c.time >= 0 ? c.Name(c.time) : "none");
  return c;
}

// Samples handed to the sink in chunks of kChunk, counted, and checked for a
// varying input.
struct ChunkedSink {
  explicit ChunkedSink(const LogSink& s) : sink(s) {
    u.reserve(kChunk);
    y.reserve(kChunk);
  }
  void Add(double uv, double yv) {
    u.push_back(uv);
    y.push_back(yv);
    ++rows;
    if (u.size() == kChunk) Flush();
  }
  void Flush() {
    if (u.empty()) return;
    constant.Add(u.data(), u.size());
    sink(u.data(), y.data(), u.size());
    u.clear();
    y.clear();
  }
  const LogSink& sink;
  ConstantCheck constant;
  std::vector<double> u, y;
  size_t rows = 0;
};

// The units of the input and output columns: LogSelect::input_unit /
// output_unit, else the units row, else the header name, else SI; and the
// layout's note of what was read.
struct ColumnUnits {
  internal::ColumnUnit input, output;
  std::string layout;
  HeaderUnits header_units = HeaderUnits::kNone;  // what the header (not a flag) says of the axis
  std::string header_units_text;
};

internal::ColumnUnit ColumnUnitOf(const std::string& given, const CsvHeader& h, const CsvColumns& cols, int c,
                                  internal::ColumnRole role, const LogSelect& sel, const std::string& where,
                                  const char* flag, bool* from_header) {
  const double cpr = sel.counts_per_rev, cpm = sel.counts_per_m;
  const bool scaled = (role == internal::ColumnRole::kInput ? sel.input_scale : sel.output_scale) != 1.0;
  *from_header = false;
  if (!given.empty()) return internal::ParseColumnUnit(given, role, cpr, cpm, false, flag, where + " (" + flag + ")");
  if (!h.units.empty() && !h.units[c].empty()) {
    *from_header = true;
    return internal::ParseColumnUnit(h.units[c], role, cpr, cpm, scaled, flag, where + " (units row)");
  }
  if (!cols.names.empty()) {
    if (auto u = internal::UnitOfColumnName(cols.names[c], role, cpr, cpm, scaled, flag, where)) {
      *from_header = true;
      return *u;
    }
  }
  return {"", role == internal::ColumnRole::kInput ? "N m" : "rad", 1.0};
}

ColumnUnits ResolveColumnUnits(const LogSelect& sel, const CsvHeader& h, const CsvColumns& cols, const std::string& path) {
  ColumnUnits u;
  bool input_header = false, output_header = false;
  u.input = ColumnUnitOf(sel.input_unit, h, cols, cols.input, internal::ColumnRole::kInput, sel,
                         path + ": input " + cols.Name(cols.input), "LogSelect::input_unit", &input_header);
  u.output = ColumnUnitOf(sel.output_unit, h, cols, cols.output, internal::ColumnRole::kOutput, sel,
                          path + ": output " + cols.Name(cols.output), "LogSelect::output_unit", &output_header);
  for (const auto* x : {&u.input, &u.output}) {
    if (x->written.empty()) continue;
    char b[120];
    std::snprintf(b, sizeof b, "; %s unit '%s' read: x %.6g to %s", x == &u.input ? "input" : "output",
                  x->written.substr(0, 24).c_str(), x->scale, x->si.c_str());
    u.layout += b;
  }
  // The axis the header says: N m and rad are rotary, N and m linear.
  for (const auto& [x, header, role] : {std::tuple{&u.input, input_header, "input"},
                                        std::tuple{&u.output, output_header, "output"}}) {
    if (!header || !x->known) continue;
    const HeaderUnits kind = x->si == "N" || x->si == "m" ? HeaderUnits::kLinear : HeaderUnits::kRotary;
    u.header_units = u.header_units == HeaderUnits::kNone || u.header_units == kind ? kind : HeaderUnits::kMixed;
    const int c = x == &u.input ? cols.input : cols.output;
    u.header_units_text += std::string(u.header_units_text.empty() ? "" : ", ") + role + " " + cols.Name(c) +
                           " in " + x->written.substr(0, 24) + " (" + (kind == HeaderUnits::kLinear ? "linear" : "rotary") + ")";
  }
  return u;
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
    for (size_t i = 0; i < ncols; ++i) ParseNumberIn(fields[i], *delim, &v[i]);
    return v;
  }();
  const std::optional<std::vector<std::string>> units_row = UnitsRow(pre, *delim, ncols);
  CsvHeader header = ReadHeader(units_row ? pre.before_last : pre.last, *delim, ncols, first_data, path);
  if (units_row) {
    header.units = *units_row;
    header.layout += ", units row at line " + std::to_string(pre.last->no);
  }
  const bool rate_given = sel.sample_rate_hz > 0.0;
  CsvColumns cols = SelectColumns(sel, header, ncols, path);
  const int ci = cols.input, co = cols.output, ct = cols.time;
  const ColumnUnits units = ResolveColumnUnits(sel, header, cols, path);
  cols.layout += units.layout;
  if (ct >= 0 && !cols.names.empty() && !rate_given && sel.time_unit.empty()) {
    const std::string unit = UnitInName(cols.names[ct] + (header.units.empty() ? "" : " " + header.units[ct]));
    if (!unit.empty()) {
      throw InputError(path + ": the time column '" + cols.names[ct].substr(0, 40) + "' looks like " +
                       (unit == "ms" ? "milliseconds" : "microseconds") + ": pass LogSelect::time_unit " + unit +
                       " (or LogSelect::time_unit s if it is in seconds)");
    }
  }
  auto col_name = [&](int c) { return cols.Name(c); };
  TimeChecker times(path, sel.max_interval_deviation, !rate_given);
  ChunkedSink out(sink);
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
      else if (!ParseNumberIn(fields[col], *delim, &v)) {
        const bool comma = !delim->decimal_comma && delim->c != ',' && fields[col].find(',') != std::string_view::npos;
        throw InputError(path + ": " + where() + ": " + Shown(fields[col]) + " is not a number" +
                         (comma ? " (a decimal comma? pass LogSelect::decimal_comma)" : ""));
      }
      if (!std::isfinite(v)) CheckFinite(v, path, where());
      return v;
    };
    const double uv = parse(ci), yv = parse(co);
    if (ct >= 0) times.AddLazy(parse(ct) * time_scale, [&] { return "line " + std::to_string(line_no); });
    out.Add(uv * units.input.scale * sel.input_scale, yv * units.output.scale * sel.output_scale);
    first = false;
  } while (reader.Next(&line));
  out.Flush();
  if (!out.constant.varies) {
    throw InputError(path + ": input " + col_name(ci) +
                     " is constant: the log has no excitation to identify from (wrong LogSelect::input_column?)");
  }
  LogInfo info;
  info.source = path;
  info.num_samples = out.rows;
  info.layout = cols.layout;
  info.header_units = units.header_units;
  info.header_units_text = units.header_units_text;
  ResolveRate(path, sel, times, ct, out.rows, ct >= 0 ? col_name(ct) : std::string(), &info);
  return info;
}

void WriteCsvLog(const std::string& tmp, double rate, const std::vector<double>& u,
                 const std::vector<double>& y, bool linear) {
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError("cannot create '" + tmp + "'");
  std::fputs(linear ? "t,force [N],position [m]\n" : "t,torque,position\n", f);
  std::string line;  // to_chars: no decimal comma under the host's locale (Python's locale.setlocale)
  int error = 0;     // errno of the first write that failed
  for (size_t k = 0; k < u.size(); ++k) {
    line.clear();
    AppendG(&line, static_cast<double>(k) / rate, 17);
    line += ',';
    AppendG(&line, u[k], 17);
    line += ',';
    AppendG(&line, y[k], 17);
    line += '\n';
    if (std::fputs(line.c_str(), f) < 0 && error == 0) error = errno;
  }
  const bool ok = std::ferror(f) == 0;
  errno = 0;
  if (std::fclose(f) != 0 && error == 0) error = errno;
  if (error != 0 || !ok) throw InputError(internal::WriteFailure(tmp, error));
}

}  // namespace zwidth::io::internal
