// io/printable.h: names shown to a person or written to JSON, against a
// reference written here from the header's rules and RFC 3629 by another
// route: each sequence decoded to its code point, then refused when overlong
// (below the least code point of its length), a surrogate (U+D800..DFFF) or
// above U+10FFFF, instead of the library's table of lead and second bytes;
// compared on hand-picked strings and 20 000 seeded random byte strings drawn
// from the bytes that matter (controls, DEL, C1 leads, continuation bytes,
// every lead byte class).
#include <cstdio>
#include <random>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "io/printable.h"

namespace zwidth::io {
namespace {

// Code point of the valid UTF-8 sequence at t[i] and its length, or length 0.
size_t Decode(std::string_view t, size_t i, unsigned* cp) {
  const unsigned char c = t[i];
  size_t n;
  unsigned v;
  if (c < 0x80) { *cp = c; return 1; }
  if ((c & 0xE0) == 0xC0) n = 2, v = c & 0x1F;
  else if ((c & 0xF0) == 0xE0) n = 3, v = c & 0x0F;
  else if ((c & 0xF8) == 0xF0) n = 4, v = c & 0x07;
  else return 0;
  if (i + n > t.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    const unsigned char d = t[i + k];
    if ((d & 0xC0) != 0x80) return 0;
    v = (v << 6) | (d & 0x3F);
  }
  const unsigned least[] = {0, 0, 0x80, 0x800, 0x10000};
  if (v < least[n] || (v >= 0xD800 && v <= 0xDFFF) || v > 0x10FFFF) return 0;
  *cp = v;
  return n;
}

std::string Hex(const char* f, unsigned v) {
  char b[16];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// mode 0: Printable, 1: PrintableLines, 2: Utf8ForJson.
std::string Reference(std::string_view t, int mode) {
  std::string out;
  for (size_t i = 0; i < t.size();) {
    unsigned cp = 0;
    const size_t n = Decode(t, i, &cp);
    if (n == 0) {
      out += Hex("\\x%02x", static_cast<unsigned char>(t[i]));
      ++i;
      continue;
    }
    const std::string_view ch = t.substr(i, n);
    i += n;
    if (mode == 2) { out += ch; continue; }
    if (cp >= 0x80 && cp <= 0x9F) out += Hex("\\u%04x", cp);
    else if (cp >= 0x20 && cp != 0x7F) out += ch;
    else if (cp == '\n') out += mode == 1 ? "\n" : "\\n";
    else if (cp == '\r') out += "\\r";
    else if (cp == '\t') out += mode == 1 ? "\t" : "\\t";  // PrintableLines keeps tabs too (see the report)
    else out += Hex("\\x%02x", cp);
  }
  return out;
}

TEST(Printable, HandPickedNames) {
  EXPECT_EQ(Printable("plain name.csv"), "plain name.csv");
  EXPECT_EQ(Printable("a\nb\rc\td"), "a\\nb\\rc\\td");
  EXPECT_EQ(Printable("\x1b[31mred"), "\\x1b[31mred");                // ANSI escape
  EXPECT_EQ(Printable("caf\xc3\xa9 \xe4\xb8\xad"), "caf\xc3\xa9 \xe4\xb8\xad");  // accents, CJK kept
  EXPECT_EQ(Printable("caf\xe9"), "caf\\xe9");                        // Latin-1
  EXPECT_EQ(Printable("\xc2\x9b" "1m"), "\\u009b1m");                 // C1 CSI
  EXPECT_EQ(Printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");            // a surrogate
  EXPECT_EQ(Printable("\xc0\xaf"), "\\xc0\\xaf");                     // overlong '/'
  EXPECT_EQ(Printable("back\\slash\x7f"), "back\\slash\\x7f");
  EXPECT_EQ(PrintableLines("line 1\nline 2\r\n"), "line 1\nline 2\\r\n");
  EXPECT_EQ(Utf8ForJson("ok\n\xff\xc3\xa9"), "ok\n\\xff\xc3\xa9");
}

TEST(Printable, RandomBytesMatchTheCodePointReference) {
  const unsigned char pool[] = {0x00, 0x07, 0x09, 0x0a, 0x0d, 0x1b, 0x20, 'a', '\\', 0x7f, 0x80, 0x8f, 0x9f, 0xa0, 0xbf,
                                0xc0, 0xc1, 0xc2, 0xc3, 0xdf, 0xe0, 0xe1, 0xed, 0xef, 0xf0, 0xf4, 0xf5, 0xff, 0x90, 0x9b};
  std::mt19937_64 rng(24);
  std::uniform_int_distribution<int> len(0, 12), pick(0, sizeof pool - 1);
  for (int k = 0; k < 20000; ++k) {
    std::string s(len(rng), '\0');
    for (char& c : s) c = static_cast<char>(pool[pick(rng)]);
    ASSERT_EQ(Printable(s), Reference(s, 0)) << k;
    ASSERT_EQ(PrintableLines(s), Reference(s, 1)) << k;
    ASSERT_EQ(Utf8ForJson(s), Reference(s, 2)) << k;
  }
}

}  // namespace
}  // namespace zwidth::io
