#include <cassert>
#include <charconv>
#include <string>
#include <cerrno>
#include <cstdio>
#include <cstring>

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

std::string WriteFailure(const std::string& written, int error) {
  // Each component "NAME.tmp-XXXXXX" (a file) or ".NAME.tmp-XXXXXX" (a folder) back to NAME.
  std::string shown, part;
  auto name = [](std::string c) {
    const size_t t = c.rfind(".tmp-");
    if (t != std::string::npos && t > 0 && c.size() - t == 11) {
      c.erase(t);
      if (c.size() > 1 && c[0] == '.') c.erase(0, 1);
    }
    return c;
  };
  for (size_t i = 0; i <= written.size(); ++i) {
    if (i == written.size() || written[i] == '/') {
      shown += name(part);
      if (i < written.size()) shown += '/';
      part.clear();
    } else {
      part += written[i];
    }
  }
  return "failed writing '" + shown + "': " + (error ? std::strerror(error) : "write error") +
         " (disk full, or a file size limit?); nothing was written: free space or write elsewhere";
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
  if (ok_ && std::fwrite(buf_.data(), 1, buf_.size(), f_) != buf_.size()) {
    ok_ = false;
    errno_ = errno;
  }
  buf_.clear();
}

void CsvFile::Close(const std::string& shown) {
  Flush();
  const bool ok = ok_ && std::ferror(f_) == 0;
  errno = 0;
  const bool closed = std::fclose(f_) == 0;
  if (!closed && errno_ == 0) errno_ = errno;
  f_ = nullptr;
  if (!closed || !ok) throw InputError(WriteFailure(shown, errno_));
}

}  // namespace zwidth::io::internal
