// Units of a text log's input and output columns, read from the header
// ("torque [mNm]", "pos (deg)", "x_mm", a units row under the header) or given
// (LogSelect::input_unit / output_unit), and the factor that turns them into
// zwidth's SI units (N m or N; rad or m). Encoder counts need
// LogSelect::counts_per_rev (rotary) or counts_per_m (linear).
#pragma once

#include <optional>
#include <string>

namespace zwidth::io::internal {

enum class ColumnRole { kInput, kOutput };  // torque/force; position (angle/length)

struct ColumnUnit {
  std::string written;  // as the file or the flag writes it, e.g. "mNm"
  std::string si;       // what it is converted to: "N m", "N", "rad", "m"
  double scale = 1.0;   // SI value = scale * file value
  // A unit of zwidth's table (N m, N, deg, mm, ...; not si, counts or one the
  // scale converts): `si` then says the axis, rotary (N m, rad) or linear (N, m).
  bool known = false;
};

// The unit a header name carries: a bracketed last word ("[mNm]", "(deg)")
// must be one zwidth knows for the role (else InputError naming the flag to
// pass); a suffix after '_', '-' or a space ("pos_deg") counts only when it is
// a known unit. nullopt when the name carries none. `flag` names the option that overrides it.
// scale_given: the user gave the column's scale (LogSelect::input_scale or
// output_scale != 1), which then converts a unit zwidth does not know.
std::optional<ColumnUnit> UnitOfColumnName(const std::string& name, ColumnRole role, double counts_per_rev,
                                           double counts_per_m, bool scale_given, const std::string& flag,
                                           const std::string& where);

// A header name's trailing bracketed unit, "torque [mNm]" or "t (s)": true
// with *base = "torque" and *unit = "mNm"; false when the name ends in no
// bracket pair (or the bracket opens the name), *base then the name. *base
// never ends in blanks.
bool SplitBracketedUnit(const std::string& name, std::string* base, std::string* unit);

// A unit written alone (a units-row field, or the flag's value). "si" (or "")
// means the column is already in SI units. Throws InputError for an unknown
// unit or counts without a counts-per value.
ColumnUnit ParseColumnUnit(const std::string& unit, ColumnRole role, double counts_per_rev, double counts_per_m,
                           bool scale_given, const std::string& flag, const std::string& where);

// True when the text reads as a unit of either role (a units row's field).
bool LooksLikeUnit(const std::string& text);

// Parses f as a number whose decimal mark is ',' (and no '.'): "0,25" -> 0.25.
bool ParseDecimalComma(std::string_view f, double* v);

}  // namespace zwidth::io::internal
