// Text the library writes is the same in every locale (issue 30): a German
// C locale (Python's locale.setlocale, a program's setlocale(LC_ALL, ""))
// makes printf's %g write 0,5, and a global C++ locale (std::locale::global)
// makes streams write 0,5 and group thousands (1.000). The writers of text
// (the report, compare, a fit's brief report) hold a ScopedCLocale while they
// print and imbue their streams with the classic locale.
#pragma once

#include <charconv>
#include <clocale>
#include <string>
#include <locale.h>

namespace zwidth {

// The C locale for this thread while it lives (uselocale): printf, strtod; other
// threads keep theirs.
class ScopedCLocale {
 public:
  ScopedCLocale() : c_(newlocale(LC_ALL_MASK, "C", nullptr)), old_(c_ ? uselocale(c_) : nullptr) {}
  ~ScopedCLocale() {
    if (c_) {
      uselocale(old_);
      freelocale(c_);
    }
  }
  ScopedCLocale(const ScopedCLocale&) = delete;
  ScopedCLocale& operator=(const ScopedCLocale&) = delete;

 private:
  locale_t c_;
  locale_t old_;
};

// v in %g (six significant digits) whatever the locale, for messages: printf's
// %g and std::to_string follow the C locale a program (or Python) chose.
inline std::string FormatG(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v, std::chars_format::general, 6);
  return std::string(b, r.ptr);
}

}  // namespace zwidth
