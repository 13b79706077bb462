#include "io/printable.h"

#include <cstdio>

namespace zwidth::io {
namespace {

// Length of the valid UTF-8 sequence at text[i] (1..4), or 0 (RFC 3629: no
// overlong forms, no surrogates, nothing above U+10FFFF).
size_t Utf8Length(std::string_view t, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(t[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  const size_t n = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
  if (n == 0 || i + n > t.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((b(i + k) & 0xC0) != 0x80) return 0;
  }
  if (c == 0xE0 && b(i + 1) < 0xA0) return 0;  // overlong
  if (c == 0xED && b(i + 1) > 0x9F) return 0;  // surrogate
  if (c == 0xF0 && b(i + 1) < 0x90) return 0;  // overlong
  if (c == 0xF4 && b(i + 1) > 0x8F) return 0;  // above U+10FFFF
  return n;
}

void AppendHex(std::string* out, const char* format, unsigned value) {
  char buf[8];
  std::snprintf(buf, sizeof buf, format, value);
  *out += buf;
}

// Walks `text`; valid UTF-8 sequences go to keep(), other bytes as \xNN.
template <typename Keep>
std::string Escape(std::string_view text, Keep keep) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    const size_t n = Utf8Length(text, i);
    if (n == 0) {
      AppendHex(&out, "\\x%02x", static_cast<unsigned char>(text[i]));
      ++i;
      continue;
    }
    keep(&out, text.substr(i, n));
    i += n;
  }
  return out;
}

std::string Printable(std::string_view text, bool keep_newlines) {
  return Escape(text, [keep_newlines](std::string* out, std::string_view ch) {
    const unsigned char c = static_cast<unsigned char>(ch[0]);
    if (ch.size() == 2 && c == 0xC2 && static_cast<unsigned char>(ch[1]) < 0xA0) {
      AppendHex(out, "\\u%04x", static_cast<unsigned char>(ch[1]));  // C1 control
    } else if (ch.size() > 1 || (c >= 0x20 && c != 0x7F)) {
      *out += ch;
    } else if (c == '\n') {
      *out += keep_newlines ? "\n" : "\\n";
    } else if (c == '\r') {
      *out += "\\r";
    } else if (c == '\t') {
      *out += keep_newlines ? "\t" : "\\t";
    } else {
      AppendHex(out, "\\x%02x", c);
    }
  });
}

}  // namespace

std::string Printable(std::string_view text) { return Printable(text, false); }
std::string PrintableLines(std::string_view text) { return Printable(text, true); }

std::string Utf8ForJson(std::string_view text) {
  return Escape(text, [](std::string* out, std::string_view ch) { *out += ch; });
}

}  // namespace zwidth::io
