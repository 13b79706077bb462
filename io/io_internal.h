// Helpers shared by the io readers and writers (internal: not installed,
// include only from io/*.cc).
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include <utility>

#include "model/friction.h"

namespace H5 { class H5Object; }

namespace zwidth::io::internal {

// The fields of `line` between the separators `sep`, untrimmed: one more
// field than separators (an empty line gives one empty field). The views
// point into `line`.
void SplitFields(std::string_view line, char sep, std::vector<std::string_view>* out);

// A scalar IEEE double attribute `name` = v on obj (a file's group or a
// dataset), closed before return so that a write error throws here.
// Defined in io/log_hdf5.cc (with the HDF5 code, see io/hdf5_api.h).
void WriteDoubleAttr(H5::H5Object& obj, const std::string& name, double v);

// Text output of numbers without printf: appends v to *out exactly as
// printf("%.<digits>g") would (std::to_chars in the general format with that
// precision is specified so, nan and inf included), and ints as "%d".
void AppendG(std::string* out, double v, int digits);
void AppendInt(std::string* out, long long v);

// A CSV file written line by line: fields separated by ',', lines ended by
// '\n', kept in a buffer written out every MiB (a response of 2^20 bins would
// otherwise sit whole in memory). InputError "cannot create '<path>'" when it
// cannot be opened, "failed writing '<shown>'" from Close when a write failed.
// The message of a write that failed on `written` (a temporary: "DIR/.OUT.tmp-XXXXXX/f.csv.tmp-XXXXXX"
// is shown as the file the user named, "DIR/OUT/f.csv"), with the system's reason (errno, e.g. "No
// space left on device") and what to do. Nothing was written.
std::string WriteFailure(const std::string& written, int error);

class CsvFile {
 public:
  explicit CsvFile(const std::string& path);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  void Text(const char* s) { buf_ += s; }
  CsvFile& G(double v, int digits) { Sep(); AppendG(&buf_, v, digits); return *this; }
  CsvFile& Int(long long v) { Sep(); AppendInt(&buf_, v); return *this; }
  void End();
  void Close(const std::string& shown);

 private:
  void Sep() { if (!first_) buf_.push_back(','); first_ = false; }
  void Flush();
  std::FILE* f_;
  std::string buf_;
  bool first_ = true, ok_ = true;
  int errno_ = 0;  // of the first write that failed
};

// The fields of model/friction.h as (name, value), in model.json's key order
// and names: what the MATLAB, Python and HDF5 exports write.
std::vector<std::pair<std::string, double>> FrictionFields(const model::Friction& f);

}  // namespace zwidth::io::internal
