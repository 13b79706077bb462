#include "io/batch_table.h"

#include <glob.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "io/atomic_file.h"
#include "io/hdf5_api.h"
#include "io/isolated.h"
#include "io/log.h"
#include "io/log_internal.h"
#include "io/model_json.h"
#include "io/printable.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

constexpr size_t kMaxTableBytes = 1u << 30;  // a manifest or table: 1 GiB (~10^6 units)

struct Record {
  int line = 0;  // 1-based line where the record starts
  std::vector<std::string> fields;
};

// RFC 4180 records; blank lines skipped. A quote inside an unquoted field, or
// a quoted field left open, is an InputError naming the line.
std::vector<Record> ParseCsv(const std::string& text, const std::string& source) {
  std::vector<Record> out;
  size_t i = 0;
  int line = 1;
  const size_t n = text.size();
  auto bad = [&](int at, const std::string& what) {
    return InputError(source + " line " + std::to_string(at) + ": " + what);
  };
  while (i < n) {
    if (text[i] == '\n' || text[i] == '\r') {  // blank line
      if (text[i] == '\r' && i + 1 < n && text[i + 1] == '\n') ++i;
      ++i, ++line;
      continue;
    }
    Record r{line, {}};
    std::string field;
    bool quoted = false;
    for (;;) {
      if (i >= n) {
        r.fields.push_back(field);
        break;
      }
      const char c = text[i];
      if (quoted) {
        if (c == '"') {
          if (i + 1 < n && text[i + 1] == '"') {
            field += '"';
            i += 2;
          } else {
            quoted = false;
            ++i;
            if (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
              throw bad(line, "text after a closing quote; quote the whole field and double a quote inside it");
            }
          }
        } else {
          if (c == '\n') ++line;
          field += c;
          ++i;
        }
        continue;
      }
      if (c == '"') {
        if (!field.empty()) throw bad(line, "a quote inside an unquoted field; quote the whole field");
        quoted = true;
        ++i;
      } else if (c == ',') {
        r.fields.push_back(field);
        field.clear();
        ++i;
      } else if (c == '\n' || c == '\r') {
        r.fields.push_back(field);
        if (c == '\r' && i + 1 < n && text[i + 1] == '\n') ++i;
        ++i, ++line;
        break;
      } else {
        field += c;
        ++i;
      }
    }
    if (quoted) throw bad(r.line, "a quoted field is never closed");
    out.push_back(std::move(r));
  }
  return out;
}

std::string Quoted(const std::string& cell) {
  if (cell.find_first_of(",\"\r\n") == std::string::npos) return cell;
  std::string q = "\"";
  for (char c : cell) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

bool IsGlob(const std::string& s) { return s.find_first_of("*?[") != std::string::npos; }

}  // namespace

std::vector<BatchEntry> ReadManifest(const std::string& path) {
  std::string text = ReadSmallFile(path, "manifest", kMaxTableBytes);
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);  // a spreadsheet's UTF-8 BOM ("it reads 'serial,path'")
  const std::string where = Printable(path);
  std::vector<Record> records = ParseCsv(text, where);
  if (records.empty()) throw InputError(where + ": an empty manifest; its first line names the columns (serial,path,...)");
  const std::vector<std::string>& header = records.front().fields;
  int serial_col = -1, path_col = -1;
  std::set<std::string> seen_columns;
  for (size_t c = 0; c < header.size(); ++c) {
    if (header[c].empty()) throw InputError(where + " line 1, column " + std::to_string(c + 1) + ": an empty column name");
    if (!seen_columns.insert(header[c]).second) {
      throw InputError(where + " line 1: column '" + Printable(header[c]) + "' is named twice");
    }
    if (header[c] == "serial") serial_col = static_cast<int>(c);
    if (header[c] == "path") path_col = static_cast<int>(c);
  }
  if (serial_col < 0 || path_col < 0) {
    throw InputError(where + " line 1: the header must name the columns 'serial' and 'path' (then any log flag "
                     "without its dashes, e.g. rate, input-column); it reads '" + Printable(text.substr(0, text.find('\n'))) + "'");
  }
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<BatchEntry> out;
  std::map<std::string, int> serial_line;
  for (size_t k = 1; k < records.size(); ++k) {
    const Record& r = records[k];
    const std::string at = where + " line " + std::to_string(r.line);
    if (r.fields.size() != header.size()) {
      throw InputError(at + ": " + std::to_string(r.fields.size()) + " fields where the header has " +
                       std::to_string(header.size()) + "; give every column (an empty one keeps the command's flag)");
    }
    BatchEntry e;
    e.serial = r.fields[serial_col];
    e.path = r.fields[path_col];
    e.origin = at;
    if (e.serial.empty()) throw InputError(at + ", column 'serial': empty; every unit needs its serial");
    if (e.path.empty()) throw InputError(at + ", column 'path': empty; every unit needs its log");
    if (auto [it, fresh] = serial_line.emplace(e.serial, r.line); !fresh) {
      throw InputError(at + ": serial '" + Printable(e.serial) + "' is already on line " + std::to_string(it->second) +
                       "; a serial names one unit (give the logs of one unit different serials, or one row)");
    }
    if (std::filesystem::path(e.path).is_relative()) e.path = (folder / e.path).string();
    for (size_t c = 0; c < header.size(); ++c) {
      if (static_cast<int>(c) == serial_col || static_cast<int>(c) == path_col || r.fields[c].empty()) continue;
      e.flags.emplace_back(header[c], r.fields[c]);
    }
    out.push_back(std::move(e));
  }
  if (out.empty()) throw InputError(where + ": no units under the header; add one line per unit (serial,path,...)");
  return out;
}

std::vector<BatchEntry> EntriesFromArguments(const std::vector<std::string>& arguments) {
  std::vector<BatchEntry> out;
  std::map<std::string, std::string> seen;  // path -> origin
  for (size_t a = 0; a < arguments.size(); ++a) {
    const std::string origin = "argument " + std::to_string(a + 1);
    std::vector<std::string> paths;
    if (IsGlob(arguments[a])) {
      glob_t g{};
      const int rc = glob(arguments[a].c_str(), 0, nullptr, &g);  // sorted by name
      for (size_t k = 0; rc == 0 && k < g.gl_pathc; ++k) paths.emplace_back(g.gl_pathv[k]);
      globfree(&g);
      if (paths.empty()) {
        throw InputError("'" + Printable(arguments[a]) + "' (" + origin + ") matches no file; check the pattern, and "
                         "quote it so that zwidth expands it (the shell may have expanded it already)");
      }
    } else {
      paths.push_back(arguments[a]);
    }
    for (const std::string& p : paths) {
      if (auto [it, fresh] = seen.emplace(p, origin); !fresh) {
        throw InputError("'" + Printable(p) + "' is named by " + it->second + " and " + origin +
                         "; give each unit's log once");
      }
      out.push_back({p, p, {}, origin});
    }
  }
  return out;
}

std::string HashInputs(const std::vector<std::string>& paths, const std::string& options) {
  std::uint64_t h = 14695981039346656037ull;
  auto add = [&h](const char* p, size_t n) {
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(p[i])) * 1099511628211ull;
  };
  auto add_size = [&](std::uint64_t n) {
    char b[8];
    for (int i = 0; i < 8; ++i) b[i] = static_cast<char>(n >> (8 * i));
    add(b, 8);
  };
  add_size(options.size());
  add(options.data(), options.size());
  for (const std::string& path : paths) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return "";
    std::ifstream in(path, std::ios::binary);
    if (!in) return "";
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) return "";
    add_size(size);
    std::vector<char> buf(1 << 16);
    std::uint64_t got = 0;
    while (in) {
      in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
      add(buf.data(), static_cast<size_t>(in.gcount()));
      got += static_cast<std::uint64_t>(in.gcount());
    }
    if (got != size) return "";  // changed while read
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

std::string FormatBatchCsv(const BatchTable& table) {
  std::string s;
  for (size_t c = 0; c < table.columns.size(); ++c) s += (c ? "," : "") + Quoted(table.columns[c]);
  s += "\n";
  for (const auto& row : table.rows) {
    for (size_t c = 0; c < table.columns.size(); ++c) {
      auto it = row.find(table.columns[c]);
      s += (c ? "," : "") + (it == row.end() ? std::string() : Quoted(it->second));
    }
    s += "\n";
  }
  return s;
}

BatchTable ParseBatchCsv(const std::string& text, const std::string& source) {
  std::vector<Record> records = ParseCsv(text, source);
  BatchTable t;
  if (records.empty()) return t;
  t.columns = records.front().fields;
  for (size_t k = 1; k < records.size(); ++k) {
    if (records[k].fields.size() != t.columns.size()) {
      throw InputError(source + " line " + std::to_string(records[k].line) + ": " +
                       std::to_string(records[k].fields.size()) + " fields where the header has " +
                       std::to_string(t.columns.size()) + " (not a table zwidth batch wrote; remove it or write elsewhere)");
    }
    std::map<std::string, std::string> row;
    for (size_t c = 0; c < t.columns.size(); ++c) row[t.columns[c]] = records[k].fields[c];
    t.rows.push_back(std::move(row));
  }
  return t;
}

bool IsHdf5TablePath(const std::string& path) { return internal::HasExtension(path, {".h5", ".hdf5", ".he5"}); }

void WriteBatchTable(const std::string& path, const BatchTable& table) {
  if (IsHdf5TablePath(path)) {
    internal::WriteHdf5Atomically(path, [&](const internal::Hdf5Api& h5, const std::string& tmp) {
      h5.write_batch_table_hdf5(tmp, table);
    });
  } else {
    WriteTextAtomically(path, FormatBatchCsv(table));
  }
}

BatchTable ReadBatchTable(const std::string& path) {
  // Not noted as an input (CheckInputFile): the table is the batch's own output, rewritten at the end.
  const std::string where = Printable(path);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(where + ": not a regular file; name the table (.csv, or .h5 for HDF5) of a batch");
  }
  if (std::filesystem::file_size(path, ec) > kMaxTableBytes) {
    throw InputError(where + ": more than 1 GiB, larger than a batch table; name the table of a batch");
  }
  if (DetectLogFormat(path) != LogFormat::kHdf5) {
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw InputError(where + ": cannot be read");
    return ParseBatchCsv(text, where);
  }
  const internal::Hdf5Api& h5 = internal::Hdf5();  // loaded before the fork
  std::string text;
  RunIsolated(
      path,
      [&](const FrameSender& send) {
        const std::string t = h5.read_batch_table_hdf5(path);
        send(t.data(), t.size());
      },
      [&](std::string_view frame) { text = frame; });
  return ParseBatchCsv(text, where);
}

BatchTable ReadPreviousBatchTable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return {};
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(Printable(path) + " is not a regular file: -o names the table (a .csv or .h5 file) to write");
  }
  BatchTable t = ReadBatchTable(path);
  if (!t.rows.empty() && (std::find(t.columns.begin(), t.columns.end(), "input_hash") == t.columns.end() ||
                          std::find(t.columns.begin(), t.columns.end(), "serial") == t.columns.end())) {
    throw InputError(Printable(path) + " exists and is not a table of zwidth batch (no serial and input_hash "
                     "columns): write the table elsewhere, or remove the file");
  }
  return t;
}

}  // namespace zwidth::io
