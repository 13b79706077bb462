// Helpers shared by the io readers and writers (internal: not installed,
// include only from io/*.cc).
#pragma once

#include <string>
#include <string_view>
#include <vector>

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
// precision is specified so, nan and inf included), and ints as "%d". About
// five times faster than fprintf for the boundary and response CSVs.
void AppendG(std::string* out, double v, int digits);
void AppendInt(std::string* out, long long v);

// Lines of a CSV: fields separated by ',', each line ended by '\n'.
class CsvLine {
 public:
  explicit CsvLine(std::string* out) : out_(out) {}
  CsvLine& G(double v, int digits) { Sep(); AppendG(out_, v, digits); return *this; }
  CsvLine& Int(long long v) { Sep(); AppendInt(out_, v); return *this; }
  void End() { out_->push_back('\n'); first_ = true; }

 private:
  void Sep() { if (!first_) out_->push_back(','); first_ = false; }
  std::string* out_;
  bool first_ = true;
};

// Writes `text` to a new file at `tmp` (binary); InputError "cannot create
// '<tmp>'" or "failed writing '<shown>'".
void WriteWholeFile(const std::string& tmp, const std::string& text, const std::string& shown);

}  // namespace zwidth::io::internal
