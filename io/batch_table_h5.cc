// The HDF5 side of io/batch_table.cc (in the plugin zwidth-hdf5.so for the
// zwidth executable, see io/hdf5_api.h): the batch table as one dataset per
// column, numbers as numbers, so that h5py or MATLAB read a column directly.
//
//   /columns            the column names in the table's order (variable-length UTF-8 strings)
//   /batch/<column>     one cell per row: float64 when every non-empty cell is a number that
//                       %.17g writes back exactly as it is (nan and inf included), else UTF-8 text
//   /empty/<column>     uint8, 1 where the cell is empty (only for a float64 column that has some)
//   root attribute zwidth_batch_table_version = 1
//
// So the text of every cell comes back as it was (ReadBatchTableHdf5 then
// FormatBatchCsv: the CSV reader of the parent parses it, io/batch_table.cc).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include <H5Cpp.h>

#include "io/batch_table.h"
#include "io/h5_safety.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "model/error.h"

namespace zwidth::io::internal {
namespace {

constexpr double kVersion = 1;
constexpr hsize_t kMaxRows = hsize_t{1} << 24;     // ~1.7e7 units
constexpr hsize_t kMaxColumns = hsize_t{1} << 16;

// The cell as its double when %.17g of it is the cell's text exactly (what
// BatchRowOf writes), so float64 keeps it; false for text and for a number
// written otherwise ("1e-3", "007"), which stays text.
bool ExactNumber(const std::string& cell, double* v) {
  if (cell.empty()) return false;
  char* end = nullptr;
  *v = std::strtod(cell.c_str(), &end);
  if (end != cell.c_str() + cell.size()) return false;
  std::string back;
  AppendG(&back, *v, 17);
  return back == cell;
}

H5::StrType Utf8() {
  H5::StrType t(H5::PredType::C_S1, H5T_VARIABLE);
  t.setCset(H5T_CSET_UTF8);
  return t;
}

void WriteStrings(H5::Group& g, const std::string& name, const std::vector<std::string>& cells) {
  const hsize_t n = cells.size();
  H5::DataSpace space(1, &n);
  std::vector<const char*> p(n);
  for (hsize_t k = 0; k < n; ++k) p[k] = cells[k].c_str();
  const H5::StrType t = Utf8();
  H5::DataSet ds = g.createDataSet(name, t, space);
  if (n > 0) ds.write(p.data(), t);
  ds.close();
}

// A 1-D dataset's length, checked local and bounded; InputError naming it.
hsize_t Length(const H5::DataSet& ds, const std::string& where, hsize_t max) {
  CheckH5DatasetLocal(ds.getId(), where, /*numbers=*/false);
  H5::DataSpace sp = ds.getSpace();
  if (sp.getSimpleExtentNdims() != 1) throw InputError(where + ": expected a 1-D dataset");
  hsize_t len = 0;
  sp.getSimpleExtentDims(&len);
  if (len > max) {
    throw InputError(where + ": " + std::to_string(len) + " values, more than a batch table holds (" +
                     std::to_string(max) + "): corrupt file?");
  }
  return len;
}

std::vector<std::string> ReadStrings(const H5::DataSet& ds, hsize_t n, const std::string& where) {
  if (ds.getTypeClass() != H5T_STRING || !ds.getStrType().isVariableStr()) {
    throw InputError(where + ": not a dataset of variable-length strings (not a table zwidth batch wrote)");
  }
  std::vector<std::string> out(n);
  if (n == 0) return out;
  std::vector<char*> p(n, nullptr);
  const H5::StrType t = Utf8();
  ds.read(p.data(), t);
  for (hsize_t k = 0; k < n; ++k) out[k] = p[k] ? p[k] : "";
  H5::DataSpace sp = ds.getSpace();
  H5::DataSet::vlenReclaim(p.data(), t, sp);
  return out;
}

}  // namespace

void WriteBatchTableHdf5(const std::string& tmp, const BatchTable& table) {
  // Names and cells checked before the file exists: a column that cannot name a
  // dataset, or a cell a C string cannot hold, is refused with nothing written.
  for (const std::string& c : table.columns) {
    if (c.empty() || c == "." || c.find('/') != std::string::npos || c.find('\0') != std::string::npos) {
      throw InputError("column '" + c + "' cannot name an HDF5 dataset; write the table as .csv");
    }
  }
  for (size_t r = 0; r < table.rows.size(); ++r) {
    for (const auto& [k, v] : table.rows[r]) {
      if (v.find('\0') != std::string::npos) {
        throw InputError("row " + std::to_string(r + 1) + ", column '" + k +
                         "': a NUL character, which an HDF5 string cannot hold; write the table as .csv");
      }
    }
  }
  H5::Exception::dontPrint();
  try {
    H5::H5File file(tmp, H5F_ACC_TRUNC);
    H5::Group root = file.openGroup("/");
    WriteStrings(root, "columns", table.columns);
    H5::Group cells = file.createGroup("/batch");
    std::optional<H5::Group> empties;
    const hsize_t n = table.rows.size();
    H5::DataSpace space(1, &n);
    for (const std::string& c : table.columns) {
      std::vector<std::string> text(n);
      std::vector<double> num(n, std::nan(""));
      std::vector<unsigned char> empty(n, 0);
      bool numeric = true, any_empty = false;
      for (hsize_t k = 0; k < n; ++k) {
        auto it = table.rows[k].find(c);
        if (it != table.rows[k].end()) text[k] = it->second;
        if (text[k].empty()) {
          empty[k] = 1, any_empty = true;
        } else if (numeric && !ExactNumber(text[k], &num[k])) {
          numeric = false;
        }
      }
      // A column of empty cells only is text: nothing says it holds numbers.
      if (!numeric || (any_empty && std::find(empty.begin(), empty.end(), 0) == empty.end())) {
        WriteStrings(cells, c, text);
        continue;
      }
      H5::DataSet ds = cells.createDataSet(c, H5::PredType::IEEE_F64LE, space);
      if (n > 0) ds.write(num.data(), H5::PredType::NATIVE_DOUBLE);
      ds.close();
      if (any_empty) {
        if (!empties) empties = file.createGroup("/empty");
        H5::DataSet e = empties->createDataSet(c, H5::PredType::STD_U8LE, space);
        e.write(empty.data(), H5::PredType::NATIVE_UCHAR);
        e.close();
      }
    }
    WriteDoubleAttr(root, "zwidth_batch_table_version", kVersion);
    // Closed inside the try: an error at flush or close (a full disk) fails
    // the write instead of vanishing in a destructor.
    if (empties) empties->close();
    cells.close();
    root.close();
    file.flush(H5F_SCOPE_GLOBAL);
    file.close();
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
}

std::string ReadBatchTableHdf5(const std::string& path) {
  H5::Exception::dontPrint();
  const std::string not_ours = " (not a table zwidth batch wrote: write the table elsewhere, or remove the file)";
  try {
    if (!H5::H5File::isHdf5(path)) throw InputError(path + ": not an HDF5 file" + not_ours);
    H5::H5File file(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, SafeH5Access());
    if (!H5LinkExists(file.getId(), path, "/columns") || !H5LinkExists(file.getId(), path, "/batch") ||
        !file.attrExists("zwidth_batch_table_version")) {
      throw InputError(path + ": no /columns, /batch and zwidth_batch_table_version" + not_ours);
    }
    const double version = ReadH5ScalarAttribute(file.getId(), "zwidth_batch_table_version", path);
    if (version != kVersion) {
      throw InputError(path + ": batch table version " + std::to_string(version) + ", this zwidth reads version 1; "
                       "read it with the zwidth that wrote it, or write the table elsewhere");
    }
    H5::DataSet cols = file.openDataSet("/columns");
    const hsize_t nc = Length(cols, path + ":/columns", kMaxColumns);
    BatchTable t;
    t.columns = ReadStrings(cols, nc, path + ":/columns");
    hsize_t n = 0;
    std::vector<std::vector<std::string>> cells(nc);
    for (hsize_t c = 0; c < nc; ++c) {
      const std::string& name = t.columns[c];
      const std::string full = "/batch/" + name;
      if (name.empty() || name.find('/') != std::string::npos || !H5LinkExists(file.getId(), path, full)) {
        throw InputError(path + ": no dataset '" + full + "' for the column '" + name + "' of /columns" + not_ours);
      }
      H5::DataSet ds = file.openDataSet(full);
      const hsize_t len = Length(ds, path + ":" + full, kMaxRows);
      if (c == 0) n = len;
      if (len != n) {
        throw InputError(path + ":" + full + ": " + std::to_string(len) + " rows where '/batch/" + t.columns[0] +
                         "' has " + std::to_string(n) + " (corrupt file?)");
      }
      if (ds.getTypeClass() == H5T_STRING) {
        cells[c] = ReadStrings(ds, n, path + ":" + full);
        continue;
      }
      if (ds.getTypeClass() != H5T_FLOAT) throw InputError(path + ":" + full + ": neither numbers nor text" + not_ours);
      std::vector<double> v(n);
      if (n > 0) ds.read(v.data(), H5::PredType::NATIVE_DOUBLE);
      std::vector<unsigned char> empty(n, 0);
      if (H5LinkExists(file.getId(), path, "/empty/" + name)) {
        H5::DataSet e = file.openDataSet("/empty/" + name);
        if (Length(e, path + ":/empty/" + name, kMaxRows) != n || e.getTypeClass() != H5T_INTEGER) {
          throw InputError(path + ":/empty/" + name + ": not " + std::to_string(n) + " integers (corrupt file?)");
        }
        if (n > 0) e.read(empty.data(), H5::PredType::NATIVE_UCHAR);
      }
      cells[c].resize(n);
      for (hsize_t k = 0; k < n; ++k) {
        if (!empty[k]) AppendG(&cells[c][k], v[k], 17);
      }
    }
    t.rows.resize(n);
    for (hsize_t k = 0; k < n; ++k) {
      for (hsize_t c = 0; c < nc; ++c) t.rows[k][t.columns[c]] = std::move(cells[c][k]);
    }
    return FormatBatchCsv(t);
  } catch (const H5::Exception& e) {
    throw InputError(path + ": HDF5 error (" + e.getDetailMsg() + "): truncated or corrupt file?");
  }
}

}  // namespace zwidth::io::internal
