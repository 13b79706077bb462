// The library's messages name option fields ("WelchOptions::window_length");
// a user meets them as a command-line flag (the CLI) or a keyword (the Python
// module). One table maps each field to both, and the two rewriters replace
// every field a message names ("" in the table: no flag / no keyword, the
// field is left as it is). tests/field_flags_check.py keeps the table whole:
// every field the library names has a row, every row a flag and a keyword
// column, every flag is registered by the CLI and every keyword is accepted
// by the Python module (tests/python).
#pragma once

#include <string>
#include <vector>

namespace zwidth::io {

struct OptionName {
  const char* field;    // Struct::field as the library's messages write it
  const char* flag;     // the CLI's flag ("--window-length"), "" when none
  const char* keyword;  // the Python keyword ("window_length"), "" when none
};
const std::vector<OptionName>& OptionNames();

// The message with each field it names replaced by its flag / its keyword.
std::string WithFlags(const std::string& message);
std::string WithKeywords(const std::string& message);

}  // namespace zwidth::io
