#include <cassert>
#include <charconv>
#include <string>
#include <cstdio>

#include "io/io_internal.h"
#include "model/error.h"

namespace zwidth::io::internal {

void AppendG(std::string* out, double v, int digits) {
  assert(digits >= 1 && digits <= 17);  // a double has 17 significant digits; the buffer fits them
  char buf[64];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, digits);
  if (r.ec != std::errc()) throw ComputationError("cannot format a number with " + std::to_string(digits) + " digits");
  out->append(buf, r.ptr);
}

void AppendInt(std::string* out, long long v) {
  char buf[24];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v);
  out->append(buf, r.ptr);
}

CsvFile::CsvFile(const std::string& path) : f_(std::fopen(path.c_str(), "wb")) {
  if (!f_) throw InputError("cannot create '" + path + "'");
}

CsvFile::~CsvFile() {
  if (f_) std::fclose(f_);
}

void CsvFile::End() {
  buf_.push_back('\n');
  first_ = true;
  if (buf_.size() >= (std::size_t{1} << 20)) Flush();
}

void CsvFile::Flush() {
  ok_ = ok_ && std::fwrite(buf_.data(), 1, buf_.size(), f_) == buf_.size();
  buf_.clear();
}

void CsvFile::Close(const std::string& shown) {
  Flush();
  const bool ok = ok_ && std::ferror(f_) == 0;
  const bool closed = std::fclose(f_) == 0;
  f_ = nullptr;
  if (!closed || !ok) throw InputError("failed writing '" + shown + "'");
}

}  // namespace zwidth::io::internal
