// Text from inputs (file names, scene and column names, a file's bytes in a
// message) shown to a person or put into JSON. A name is data: it must not
// move the cursor, forge a line of the output or change the terminal's colours
// (ANSI escapes), and a file name that is not UTF-8 (Latin-1) must not make a
// JSON writer fail after all the work.
#pragma once

#include <string>
#include <string_view>

namespace zwidth::io {

// `text` with every byte that a terminal would obey shown instead: C0 controls
// and DEL as \n, \r, \t or \xNN; the C1 controls U+0080..U+009F (which some
// terminals take as escapes) as \u0080..\u009f; a byte that is not part of
// valid UTF-8 as \xNN. Printable UTF-8 (accents, CJK) and backslashes are kept.
std::string Printable(std::string_view text);
// The same for a report of several lines: '\n' is kept (the line ends the
// program itself wrote), every other control is shown.
std::string PrintableLines(std::string_view text);

// `text` as valid UTF-8 for a JSON string: bytes that are not part of valid
// UTF-8 become \xNN (four characters); everything else, controls included
// (JSON escapes them itself), is kept.
std::string Utf8ForJson(std::string_view text);

}  // namespace zwidth::io
