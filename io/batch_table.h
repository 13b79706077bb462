// The files of `zwidth batch`: the manifest of units it reads (CSV: serial,
// path and per-unit log flags), the logs named by paths and globs, the
// fingerprint of a unit's inputs that a re-run compares to resume, and the
// result table (CSV, one row per unit, cells as text) it writes and reads
// back (CSV or HDF5). The table's cells come from analysis/batch.h; here
// they are text.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace zwidth::io {

// One unit of a batch as named by the user: its key, its log and the log flags
// of its own (a manifest's extra columns: "rate" -> "1000" for --rate 1000).
struct BatchEntry {
  std::string serial;                                      // the table's key, unique in a batch
  std::string path;                                        // the log
  std::vector<std::pair<std::string, std::string>> flags;  // column name (a flag without "--"), value as typed
  std::string origin;                                      // where it was named: "units.csv line 4", "argument 2"
};

// A manifest: CSV with a header line naming the columns "serial" and "path"
// (both required, any order) and any others, each a log flag without its
// dashes; a value left empty keeps the command's flag. A relative path is
// taken from the manifest's folder. Blank lines are skipped; fields may be
// quoted as RFC 4180 ("a,b", "say ""x"""). InputError naming the file, line
// and column for a missing column, a row with another number of fields, an
// empty serial or path, or a serial given twice.
std::vector<BatchEntry> ReadManifest(const std::string& path);

// Log arguments: each a path, or a glob (with * ? [) expanded in name order;
// a glob that matches nothing is an InputError. The serial of each is its
// path as given or matched. A path given twice (after expansion) is an
// InputError naming both arguments.
std::vector<BatchEntry> EntriesFromArguments(const std::vector<std::string>& arguments);

// FNV-1a (64 bits) of `options` then of each file's bytes (size-prefixed), as
// 16 hex digits: what a re-run compares to skip a unit done with the same
// inputs and options. "" when a file cannot be read (the unit is then run).
std::string HashInputs(const std::vector<std::string>& paths, const std::string& options);

// A table of text cells: columns in order, rows as column -> cell (a column
// a row lacks is written empty).
struct BatchTable {
  std::vector<std::string> columns;
  std::vector<std::map<std::string, std::string>> rows;
};
// CSV text: the header, then one line per row; a cell with a comma, quote,
// CR or LF is quoted (RFC 4180).
std::string FormatBatchCsv(const BatchTable& table);
// Parses FormatBatchCsv's text (a previous run's table, to resume);
// InputError naming `source` and the line for a malformed one.
BatchTable ParseBatchCsv(const std::string& text, const std::string& source);

// Whether a table at `path` is written as HDF5: its name ends .h5, .hdf5 or
// .he5 (any case), as WriteLog chooses; else CSV.
bool IsHdf5TablePath(const std::string& path);
// Writes the table to `path` atomically (a temporary file renamed: nothing
// half-written): HDF5 by IsHdf5TablePath, else FormatBatchCsv's text. The
// HDF5 file holds the same columns and cells (io/batch_table_h5.cc):
//   /columns          the column names in order (variable-length UTF-8 strings)
//   /batch/<column>   one cell per row: float64 when every non-empty cell is a
//                     number that %.17g writes back as it is (the numbers of
//                     BatchRowOf, nan included), else UTF-8 text
//   /empty/<column>   uint8, 1 where a float64 column's cell is empty
//   root attribute zwidth_batch_table_version = 1
// so ReadBatchTable gives back every cell's text. HDF5 needs zwidth::hdf5
// (io/hdf5_api.h). InputError for a column that cannot name a dataset ('/')
// or a cell holding a NUL (write .csv then), or a failed write.
void WriteBatchTable(const std::string& path, const BatchTable& table);
// Reads a table WriteBatchTable wrote: HDF5 when the file has HDF5's
// signature (parsed in a child process, io/isolated.h), else CSV
// (ParseBatchCsv); a file of at most 1 GiB. InputError naming the file for
// a file that is no such table.
BatchTable ReadBatchTable(const std::string& path);
// The table of an earlier batch at `path` (its -o), to resume from: empty
// when no file is there; InputError when `path` is no regular file, or a
// table without the serial and input_hash columns of zwidth batch (then -o
// names some other file, which a batch must not overwrite).
BatchTable ReadPreviousBatchTable(const std::string& path);

}  // namespace zwidth::io
