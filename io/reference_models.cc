#include "io/reference_models.h"

#include <charconv>
#include <stdexcept>
#include <string>
#include <string_view>

#include "model/error.h"

namespace zwidth::io {
namespace internal {
extern const std::string_view kTable1Json;  // generated from datasets/phantom/table1.json
extern const std::string_view kTable2Csv;   // generated from datasets/phantom/table2.csv
}  // namespace internal

ModelFile Table1Model() {
  static const ModelFile table1 = ParseModelJson(std::string(internal::kTable1Json), "built-in Table I");
  return table1;
}

ModelFile ReadReferenceModel(const std::string& spec, const std::string& what, bool* is_table1) {
  const bool t1 = spec == "table1";
  if (is_table1) *is_table1 = t1;
  return t1 ? Table1Model() : ReadModelJsonFor(spec, what);
}

std::vector<Table2Point> Table2Points() {
  // Columns delay_ms,B,K_cr,f_cr_hz,note. The paper samples at T = 1 ms, so the
  // delay in ms is the delay in samples. Rows with a note are the two misprinted
  // ones (see the CSV and the paper's README) and are left out.
  std::vector<Table2Point> points;
  std::string_view text = internal::kTable2Csv;
  bool header = true;
  while (!text.empty()) {
    const size_t eol = text.find('\n');
    std::string_view line = text.substr(0, eol);
    text = eol == std::string_view::npos ? std::string_view{} : text.substr(eol + 1);
    if (header || line.empty()) { header = false; continue; }
    double v[4];
    size_t pos = 0;
    for (double& x : v) {
      const size_t comma = line.find(',', pos);
      const std::string_view field = line.substr(pos, comma - pos);
      if (std::from_chars(field.data(), field.data() + field.size(), x).ec != std::errc{})
        throw std::logic_error("built-in Table II: bad field '" + std::string(field) + "'");
      pos = comma + 1;
    }
    const std::string_view note = line.substr(pos);
    if (note.find_first_not_of(" \r") != std::string_view::npos) continue;
    points.push_back({static_cast<int>(v[0]), v[1], v[2], v[3]});
  }
  return points;
}

}  // namespace zwidth::io
