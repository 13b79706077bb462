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

void WriteWholeFile(const std::string& tmp, const std::string& text, const std::string& shown) {
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError("cannot create '" + tmp + "'");
  const bool wrote = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::ferror(f) == 0;
  if (std::fclose(f) != 0 || !wrote) throw InputError("failed writing '" + shown + "'");
}

}  // namespace zwidth::io::internal
