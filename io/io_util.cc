#include "io/io_internal.h"

namespace zwidth::io::internal {

void SplitFields(std::string_view line, char sep, std::vector<std::string_view>* out) {
  out->clear();
  size_t start = 0;
  while (true) {
    const size_t p = line.find(sep, start);
    out->push_back(line.substr(start, p == std::string_view::npos ? std::string_view::npos : p - start));
    if (p == std::string_view::npos) return;
    start = p + 1;
  }
}

}  // namespace zwidth::io::internal
