#include "io/log.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <memory>
#include <sstream>

#include <sys/stat.h>

#include <H5Cpp.h>
#include <matio.h>

#include "io/atomic_file.h"
#include "io/h5_safety.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "io/log_internal.h"
#include "model/error.h"


namespace zwidth::io::internal {
namespace {

// ---- MATLAB .mat (v5 and v7.3, through libmatio) ---------------------------

struct MatCloser { void operator()(mat_t* m) const { if (m) Mat_Close(m); } };
struct VarFree { void operator()(matvar_t* v) const { if (v) Mat_VarFree(v); } };

std::string MatVariables(mat_t* mat) {
  Mat_Rewind(mat);
  std::string list;
  int n = 0;
  while (matvar_t* v = Mat_VarReadNextInfo(mat)) {
    if (n < 12) list += (n ? ", " : "") + std::string(v->name ? v->name : "?").substr(0, 24);
    ++n;
    Mat_VarFree(v);
  }
  if (n > 12) list += ", ...";
  return n ? list : "none";
}

// ---- MAT v5 before libmatio reads it ---------------------------------------
//
// libmatio trusts a v5 file's sizes: a variable cut short was read with its
// tail uninitialised (exit 0), a 1.8 MB zlib bomb expanded for 20 s into
// 2.8 GB. So the top-level data elements are walked here first: after the
// 128-byte header, each is an 8-byte tag (type, byte count) and its bytes
// (miMATRIX padded to 8, miCOMPRESSED not).
constexpr uint32_t kMiMatrix = 14, kMiCompressed = 15;
// deflate's largest expansion (RFC 1951: at most 258 bytes from 2 bits), so
// no valid compressed variable declares more bytes than this times its own.
constexpr double kMaxZlibRatio = 1032.0;

struct MatElement {
  uint32_t type = 0;
  uint64_t offset = 0, size = 0;  // of the tag; bytes after it
};

std::vector<MatElement> MatV5Elements(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(0, std::ios::end);
  const uint64_t file_size = static_cast<uint64_t>(in.tellg());
  char header[128];
  in.seekg(0);
  if (!in.read(header, sizeof header)) throw InputError(path + ": a MATLAB file shorter than its 128-byte header (truncated)");
  const bool swap = header[126] == 'M' && header[127] == 'I';  // written on a machine of the other byte order
  std::vector<MatElement> out;
  for (uint64_t off = 128; off + 8 <= file_size;) {
    unsigned char tag[8];
    in.seekg(static_cast<std::streamoff>(off));
    if (!in.read(reinterpret_cast<char*>(tag), 8)) break;
    auto word = [&](int at) {
      uint32_t v = 0;
      for (int k = 0; k < 4; ++k) v |= uint32_t{tag[at + (swap ? 3 - k : k)]} << (8 * k);
      return v;
    };
    MatElement e{word(0), off, word(4)};
    if (e.type != kMiMatrix && e.type != kMiCompressed) {
      throw InputError(path + ": byte " + std::to_string(off) + ": not a MATLAB variable (data type " +
                       std::to_string(e.type) + "): a corrupt file");
    }
    if (off + 8 + e.size > file_size) {
      throw InputError(path + ": truncated: the variable at byte " + std::to_string(off) + " declares " +
                       std::to_string(e.size) + " bytes, but the file ends " + std::to_string(file_size - off - 8) +
                       " bytes after its tag (an interrupted copy or save?); copy or save it again");
    }
    out.push_back(e);
    off += 8 + e.size + (e.type == kMiMatrix ? (8 - e.size % 8) % 8 : 0);
  }
  return out;
}

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.0f", v);
  return b;
}

size_t MatClassBytes(matio_classes c) {
  switch (c) {
    case MAT_C_DOUBLE: case MAT_C_INT64: case MAT_C_UINT64: return 8;
    case MAT_C_SINGLE: case MAT_C_INT32: case MAT_C_UINT32: return 4;
    case MAT_C_INT16: case MAT_C_UINT16: case MAT_C_CHAR: return 2;
    default: return 1;
  }
}

// InputError when the v5 variable `info` (the index-th element) declares more
// values than zwidth reads, more than its element holds (uncompressed), or more
// than its compressed bytes can expand to.
void CheckMatV5Sizes(const std::string& path, const matvar_t* info, const MatElement& e) {
  double values = 1.0;
  for (int i = 0; i < info->rank; ++i) values *= static_cast<double>(info->dims[i]);
  const std::string name = std::string(info->name ? info->name : "?").substr(0, 40);
  if (values > static_cast<double>(kMaxLogSamples)) {
    throw InputError(path + ": variable '" + name + "' declares " + Num(values) + " values, more than zwidth reads (" +
                     std::to_string(kMaxLogSamples) + "); split the log");
  }
  if (info->class_type == MAT_C_STRUCT || info->class_type == MAT_C_CELL || info->class_type == MAT_C_SPARSE) return;
  const double bytes = values * static_cast<double>(MatClassBytes(info->class_type)) * (info->isComplex ? 2 : 1);
  if (e.type == kMiMatrix && bytes > static_cast<double>(e.size)) {
    throw InputError(path + ": variable '" + name + "' declares " + Num(values) + " values (" + Num(bytes) +
                     " bytes) but holds " + std::to_string(e.size) + " bytes: a truncated or corrupt file");
  }
  if (e.type == kMiCompressed && bytes > kMaxZlibRatio * static_cast<double>(e.size) + 4096.0) {
    throw InputError(path + ": variable '" + name + "' declares " + Num(values) + " values (" + Num(bytes) +
                     " bytes) from " + std::to_string(e.size) + " compressed bytes, more than zlib can expand "
                     "(1032:1): a corrupt or hostile file, not read");
  }
}

// Every v5 variable's declared size against the file, before any is read.
void CheckMatV5File(const std::string& path, mat_t* mat) {
  const std::vector<MatElement> elements = MatV5Elements(path);
  Mat_Rewind(mat);
  for (size_t k = 0; k < elements.size(); ++k) {
    std::unique_ptr<matvar_t, VarFree> info(Mat_VarReadNextInfo(mat));
    if (!info) break;
    CheckMatV5Sizes(path, info.get(), elements[k]);
  }
  Mat_Rewind(mat);
}

// What a variable that is no plain numeric vector is, for the message.
std::string MatKind(const matvar_t* v) {
  switch (v->class_type) {
    case MAT_C_SPARSE: return "a sparse matrix (save it full: u = full(u))";
    case MAT_C_CELL: return "a cell array (save each signal as a numeric vector)";
    case MAT_C_CHAR: return "text (a char array), not samples";
    case MAT_C_STRUCT: return "a struct (name one of its fields: s.field)";
    case MAT_C_OBJECT: case MAT_C_FUNCTION: case MAT_C_OPAQUE: return "a MATLAB object, not samples";
    default: return "not numeric (class " + std::to_string(static_cast<int>(v->class_type)) + ")";
  }
}

// The variable "name" or the field "name.field" of a struct, as doubles.
// Returns false when it does not exist (and required is false).
bool ReadMatVector(mat_t* mat, const std::string& path, const std::string& spec, const char* flag,
                   std::vector<double>* out) {
  const size_t dot = spec.find('.');
  const std::string var = spec.substr(0, dot);
  std::unique_ptr<matvar_t, VarFree> info(Mat_VarReadInfo(mat, var.c_str()));
  if (!info) return false;
  std::unique_ptr<matvar_t, VarFree> whole(Mat_VarRead(mat, var.c_str()));
  if (!whole) throw InputError(path + ": variable '" + var.substr(0, 40) + "' cannot be read (corrupt file?)");
  matvar_t* v = whole.get();
  if (dot != std::string::npos) {
    if (v->class_type != MAT_C_STRUCT) {
      throw InputError(path + ": '" + var.substr(0, 40) + "' is not a struct; " + flag + " " + spec.substr(0, 40) +
                       " names a field of one");
    }
    size_t elements = 1;
    for (int i = 0; i < v->rank; ++i) elements *= v->dims[i];
    if (elements != 1) {
      throw InputError(path + ": '" + var.substr(0, 40) + "' is an array of " + std::to_string(elements) +
                       " structs; zwidth reads one struct's fields (save s(1), or its fields as variables)");
    }
    v = Mat_VarGetStructFieldByName(v, spec.substr(dot + 1).c_str(), 0);
    if (!v) {
      std::string fields;
      const size_t nf = Mat_VarGetNumberOfFields(whole.get());
      char* const* names = Mat_VarGetStructFieldnames(whole.get());
      for (size_t i = 0; names && i < nf && i < 12; ++i) {
        if (i) fields += ", ";
        fields += std::string(names[i]).substr(0, 24);
      }
      throw InputError(path + ": struct '" + var.substr(0, 40) + "' has no field '" + spec.substr(dot + 1, 40) +
                       "' (fields: " + fields + "); choose one with " + flag);
    }
  }
  size_t n = 1;
  int long_dims = 0;
  for (int i = 0; i < v->rank; ++i) {
    n *= v->dims[i];
    if (v->dims[i] > 1) ++long_dims;
  }
  if (v->class_type == MAT_C_SPARSE || v->class_type == MAT_C_CELL || v->class_type == MAT_C_STRUCT ||
      v->class_type == MAT_C_CHAR) {
    throw InputError(path + ": '" + spec.substr(0, 40) + "' is " + MatKind(v));
  }
  // A logical array (u > 0) is read by libmatio as uint8 0/1: no torque or
  // position, and an HDF5 log's boolean dataset is refused likewise.
  if (v->isLogical) {
    throw InputError(path + ": '" + spec.substr(0, 40) + "' is a logical array (true/false), not samples: save the "
                     "signal itself as numbers (double)");
  }
  if (v->isComplex || long_dims > 1 || !v->data) {
    std::string shape;
    for (int i = 0; i < v->rank; ++i) {
      if (i) shape += 'x';
      shape += std::to_string(v->dims[i]);
    }
    throw InputError(path + ": '" + spec.substr(0, 40) + "' is " + (v->isComplex ? "complex " : "") + shape +
                     "; expected a real vector (one signal per variable; save columns as separate variables)");
  }
  out->resize(n);
  auto copy = [&](auto* p) { for (size_t i = 0; i < n; ++i) (*out)[i] = static_cast<double>(p[i]); };
  switch (v->class_type) {
    case MAT_C_DOUBLE: copy(static_cast<const double*>(v->data)); break;
    case MAT_C_SINGLE: copy(static_cast<const float*>(v->data)); break;
    case MAT_C_INT8: copy(static_cast<const int8_t*>(v->data)); break;
    case MAT_C_UINT8: copy(static_cast<const uint8_t*>(v->data)); break;
    case MAT_C_INT16: copy(static_cast<const int16_t*>(v->data)); break;
    case MAT_C_UINT16: copy(static_cast<const uint16_t*>(v->data)); break;
    case MAT_C_INT32: copy(static_cast<const int32_t*>(v->data)); break;
    case MAT_C_UINT32: copy(static_cast<const uint32_t*>(v->data)); break;
    case MAT_C_INT64: copy(static_cast<const int64_t*>(v->data)); break;
    case MAT_C_UINT64: copy(static_cast<const uint64_t*>(v->data)); break;
    default:
      throw InputError(path + ": '" + spec.substr(0, 40) + "' is " + MatKind(v));
  }
  return true;
}

// A v7.3 file is an HDF5 file behind a 512-byte header: read by the HDF5
// reader, with all of its safeguards (no external link, external storage or
// virtual dataset; declared sizes against what was written), variable "u" as
// dataset "/u" and struct field "s.u" as "/s/u". Its messages name the .mat
// flags.
LogInfo StreamMat73AsHdf5(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  auto dataset = [](std::string spec) {
    for (char& c : spec) if (c == '.') c = '/';
    return "/" + spec;
  };
  try {  // a variable that is not there: named with the file's variables, as for v5
    H5::Exception::dontPrint();
    H5::H5File file(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, SafeH5Access());
    std::string names;
    const hsize_t n = file.getNumObjs();
    for (hsize_t i = 0; i < n && i < 12; ++i) names += (i ? ", " : "") + file.getObjnameByIdx(i).substr(0, 24);
    if (n > 12) names += ", ...";
    for (const auto& [spec, flag] : {std::pair{sel.input_column, "LogSelect::input_column"},
                                     std::pair{sel.output_column, "LogSelect::output_column"}}) {
      if (!H5LinkExists(file.getId(), path, dataset(spec))) {
        throw InputError(path + ": no variable '" + spec.substr(0, 40) + "' in this MATLAB v7.3 file (variables: " +
                         (names.empty() ? "none" : names) + "); choose one with " + flag);
      }
    }
  } catch (const H5::Exception& e) {
    throw InputError(path + ": a MATLAB v7.3 file that HDF5 cannot open (truncated, corrupt, or open for writing "
                     "by another program)");
  }
  LogSelect h = sel;
  h.input_dataset = dataset(sel.input_column);
  h.output_dataset = dataset(sel.output_column);
  h.time_dataset = sel.time_column == "none" ? "/.zwidth-no-time-variable" : dataset(sel.time_column);
  try {
    return StreamHdf5InProcess(path, h, sink);
  } catch (const H5::Exception& e) {
    throw InputError(path + ": a MATLAB v7.3 file that HDF5 cannot read (" + e.getDetailMsg() + "): corrupt?");
  } catch (const InputError& e) {
    std::string m = e.what();
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"LogSelect::input_dataset", "LogSelect::input_column"},
                                   {"LogSelect::output_dataset", "LogSelect::output_column"},
                                   {"LogSelect::time_dataset", "LogSelect::time_column"}}) {
      for (size_t at = m.find(from); at != std::string::npos; at = m.find(from, at + to.size())) m.replace(at, from.size(), to);
    }
    throw InputError(m + " (a MATLAB v7.3 file)");
  }
}

// The text of a char variable (a row, or row `row` of a char matrix), trailing blanks dropped.
std::string MatText(const matvar_t* v, size_t row = 0) {
  if (v->class_type != MAT_C_CHAR || v->rank != 2 || !v->data) return "";
  const size_t rows = v->dims[0], cols = v->dims[1];
  std::string out;
  for (size_t c = 0; c < cols && row < rows; ++c) {
    const size_t at = c * rows + row;
    const unsigned ch = v->data_type == MAT_T_UINT16 || v->data_type == MAT_T_UTF16
                            ? static_cast<const uint16_t*>(v->data)[at]
                            : static_cast<const uint8_t*>(v->data)[at];
    out += ch < 0x80 ? static_cast<char>(ch) : '?';
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == '\0')) out.pop_back();
  return out;
}

// A log saved as one matrix with named columns (issue 26): `data` (N x k,
// double) and `columns` (a cell array of k names, or a k-row char matrix), as
// Octave's save('-v7', 'log.mat', 'data', 'columns') of data = [t u y],
// columns = {'t', 'torque', 'position'}; LogSelect's input/output/time_column
// name the columns. False when the file holds no such pair.
bool ReadMatColumns(mat_t* mat, const std::string& path, const LogSelect& sel, std::vector<double>* u,
                    std::vector<double>* y, std::vector<double>* t, bool* have_time) {
  std::unique_ptr<matvar_t, VarFree> data(Mat_VarRead(mat, "data")), names(Mat_VarRead(mat, "columns"));
  if (!data || !names) return false;
  if (data->class_type != MAT_C_DOUBLE || data->rank != 2 || data->isComplex || !data->data) {
    throw InputError(path + ": variable 'data' must be a real double matrix, one column per signal");
  }
  const size_t n = data->dims[0], k = data->dims[1];
  std::vector<std::string> list;
  for (size_t j = 0; j < k; ++j) {
    if (names->class_type == MAT_C_CELL) {
      const matvar_t* c = Mat_VarGetCell(names.get(), static_cast<int>(j));
      list.push_back(c ? MatText(c) : "");
    } else {
      list.push_back(MatText(names.get(), j));
    }
  }
  std::string all;
  for (const std::string& l : list) all += (all.empty() ? "" : ", ") + l.substr(0, 24);
  const double* d = static_cast<const double*>(data->data);
  auto column = [&](const std::string& name, const char* flag, std::vector<double>* out, bool required) {
    for (size_t j = 0; j < k; ++j) {
      if (list[j] != name) continue;
      out->assign(d + j * n, d + (j + 1) * n);
      return true;
    }
    if (required) {
      throw InputError(path + ": 'data' has no column '" + name.substr(0, 40) + "' (columns: " + all +
                       "); choose one with " + flag);
    }
    return false;
  };
  column(sel.input_column, "LogSelect::input_column", u, true);
  column(sel.output_column, "LogSelect::output_column", y, true);
  *have_time = sel.time_column != "none" && column(sel.time_column, "LogSelect::time_column", t, sel.sample_rate_hz <= 0.0);
  return true;
}

}  // namespace

LogInfo StreamMatInProcess(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  Mat_LogInitFunc("zwidth", [](int, char*) {});  // no stderr chatter from libmatio
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(path + ": cannot open as a MATLAB .mat file (truncated or corrupt?)");
  const int file_version = Mat_GetVersion(mat.get());
  if (file_version == MAT_FT_MAT73) {
    mat.reset();
    return StreamMat73AsHdf5(path, sel, sink);
  }
  if (file_version == MAT_FT_MAT4) {
    throw InputError(path + ": a MATLAB v4 file (save -v4), which zwidth does not read: save it again as v5, v7 "
                     "or v7.3 (save -v7)");
  }
  CheckMatV5File(path, mat.get());
  const char* version = "v5/v7";
  std::vector<double> u, y, t;
  auto need = [&](const std::string& spec, const char* flag, std::vector<double>* v) {
    if (!ReadMatVector(mat.get(), path, spec, flag, v)) {
      throw InputError(path + ": no variable '" + spec.substr(0, 40) + "' in this MATLAB " + version +
                       " file (variables: " + MatVariables(mat.get()) + "); choose one with " + flag);
    }
  };
  const bool rate_given = sel.sample_rate_hz > 0.0;
  bool have_time = false;
  const bool matrix = !std::unique_ptr<matvar_t, VarFree>(Mat_VarReadInfo(mat.get(), sel.input_column.c_str())) &&
                      ReadMatColumns(mat.get(), path, sel, &u, &y, &t, &have_time);
  if (!matrix) {
    need(sel.input_column, "LogSelect::input_column", &u);
    need(sel.output_column, "LogSelect::output_column", &y);
  }
  if (!matrix && sel.time_column != "none") {
    have_time = ReadMatVector(mat.get(), path, sel.time_column, "LogSelect::time_column", &t);
    if (!have_time && !rate_given) {
      throw InputError(path + ": no time variable '" + sel.time_column.substr(0, 40) + "' (variables: " +
                       MatVariables(mat.get()) + "); choose one with LogSelect::time_column, or pass LogSelect::sample_rate_hz");
    }
  }
  if (u.size() != y.size() || (have_time && t.size() != u.size())) {
    throw InputError(path + ": the variables have different lengths (input " + std::to_string(u.size()) +
                     ", output " + std::to_string(y.size()) + (have_time ? ", time " + std::to_string(t.size()) : "") + ")");
  }
  if (u.empty()) throw InputError(path + ": variable '" + sel.input_column.substr(0, 40) + "' is empty");
  TimeChecker times(path, sel.max_interval_deviation, !rate_given);
  for (size_t i = 0; i < u.size(); ++i) {
    const std::string where = "sample " + std::to_string(i + 1);
    CheckFinite(u[i], path + ":" + sel.input_column, where);
    CheckFinite(y[i], path + ":" + sel.output_column, where);
    if (have_time) {
      CheckFinite(t[i], path + ":" + sel.time_column, where);
      times.Add(t[i], where + " of " + sel.time_column);
    }
  }
  ConstantCheck constant;
  constant.Add(u.data(), u.size());
  if (!constant.varies) {
    throw InputError(path + ": input '" + sel.input_column.substr(0, 40) + "' is constant: no excitation to identify from");
  }
  for (size_t off = 0; off < u.size(); off += kChunk) sink(u.data() + off, y.data() + off, std::min(kChunk, u.size() - off));
  LogInfo info;
  info.source = path;
  info.num_samples = u.size();
  info.sample_rate_hz = rate_given ? sel.sample_rate_hz : times.Rate();
  if (!(info.sample_rate_hz > 0.0) || !std::isfinite(info.sample_rate_hz)) {
    throw InputError(path + ": cannot tell the sample rate (fewer than 2 samples?); pass LogSelect::sample_rate_hz");
  }
  return info;
}

// The v5 size checks and the variable list above, for the response reader
// (io/frf_mat.cc).
void CheckMatV5Variables(const std::string& path, mat_t* mat) { CheckMatV5File(path, mat); }
std::string MatVariableNames(mat_t* mat) { return MatVariables(mat); }

}  // namespace zwidth::io::internal
