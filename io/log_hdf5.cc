#include "io/log.h"

#include <algorithm>
#include <cerrno>
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

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <H5Cpp.h>

#include "io/atomic_file.h"
#include "io/h5_safety.h"
#include "io/io_internal.h"
#include "io/log_internal.h"
#include "model/error.h"


namespace zwidth::io {
namespace {

std::string H5Where(const std::string& path, const std::string& ds) { return path + ":" + ds; }

H5::DataSet OpenDataset(H5::H5File& file, const std::string& path, const std::string& name,
                        const char* flag) {
  if (!internal::H5LinkExists(file.getId(), path, name)) {
    throw InputError(path + ": no dataset '" + name + "'; choose one with " + flag);
  }
  H5::DataSet ds;
  try {
    ds = file.openDataSet(name);
  } catch (const H5::Exception&) {
    // A group (Octave's save -hdf5 stores a variable as a group of type and
    // value): name its members, so the dataset to pass is plain.
    try {
      if (file.childObjType(name) == H5O_TYPE_GROUP) {
        H5::Group g = file.openGroup(name);
        const hsize_t n = g.getNumObjs();
        std::string members, example;
        for (hsize_t i = 0; i < n && i < 10; ++i) {
          const std::string m = g.getObjnameByIdx(i).substr(0, 40);
          members += (i ? ", " : "") + m;
          if (example.empty() || m == "value") example = m;  // Octave's data is in "value"
        }
        if (n > 10) members += ", ...";
        throw InputError(path + ": '" + name + "' is a group, not a dataset (members: " + members + "); pass " +
                         flag + " " + name + "/" + (example.empty() ? "MEMBER" : example));
      }
    } catch (const H5::Exception&) {
    }
    throw InputError(path + ": '" + name + "' is not a readable dataset");
  }
  internal::CheckH5DatasetLocal(ds.getId(), H5Where(path, name));
  const H5T_class_t cls = ds.getTypeClass();
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
    throw InputError(H5Where(path, name) + ": not a numeric dataset (HDF5 type class " + std::to_string(cls) +
                     "); expected floating-point or integer samples");
  }
  return ds;
}

size_t Length1D(const H5::DataSet& ds, const std::string& where) {
  H5::DataSpace sp = ds.getSpace();
  const int rank = sp.getSimpleExtentNdims();
  std::vector<hsize_t> dims(std::max(rank, 1));
  sp.getSimpleExtentDims(dims.data());
  hsize_t n = 0;
  if (rank == 1) n = dims[0];
  else if (rank == 2 && (dims[0] == 1 || dims[1] == 1)) n = dims[0] * dims[1];
  else throw InputError(where + ": expected a 1-D dataset, found rank " + std::to_string(rank));
  if (n > kMaxLogSamples) {
    throw InputError(where + ": declares " + std::to_string(n) + " samples, more than zwidth reads (" +
                     std::to_string(kMaxLogSamples) + "); split the log");
  }
  return n;
}

void ReadSlab(const H5::DataSet& ds, hsize_t offset, hsize_t count, double* out,
              const std::string& where) {
  H5::DataSpace file_space = ds.getSpace();
  const int rank = file_space.getSimpleExtentNdims();
  std::vector<hsize_t> dims(rank);
  file_space.getSimpleExtentDims(dims.data());
  std::vector<hsize_t> off(rank, 0), cnt(rank, 1);
  const int axis = (rank == 2 && dims[0] == 1) ? 1 : 0;
  off[axis] = offset;
  cnt[axis] = count;
  file_space.selectHyperslab(H5S_SELECT_SET, cnt.data(), off.data());
  H5::DataSpace mem_space(1, &count);
  try {
    ds.read(out, H5::PredType::NATIVE_DOUBLE, mem_space, file_space);
  } catch (const H5::Exception&) {
    throw InputError(where + ": cannot read (truncated or corrupt file?)");
  }
}

// A logger that preallocates its datasets and stops early leaves parts never
// written, which read back as fill values: a 70 kB file can declare 1e10
// samples. Refused here, before streaming: every chunk of a chunked dataset
// must be allocated, and all of a contiguous one.
void CheckWritten(const H5::DataSet& ds, const std::string& where) {
  const H5::DSetCreatPropList plist = ds.getCreatePlist();
  H5::DataSpace sp = ds.getSpace();
  const int rank = sp.getSimpleExtentNdims();
  std::vector<hsize_t> dims(std::max(rank, 1), 1);
  sp.getSimpleExtentDims(dims.data());
  hsize_t elements = 1;
  for (int i = 0; i < rank; ++i) elements *= dims[i];
  if (plist.getLayout() == H5D_CHUNKED) {
    std::vector<hsize_t> chunk(std::max(rank, 1), 1);
    plist.getChunk(rank, chunk.data());
    hsize_t expected = 1, allocated = 0;
    for (int i = 0; i < rank; ++i) expected *= (dims[i] + chunk[i] - 1) / std::max<hsize_t>(chunk[i], 1);
    if (H5Dget_num_chunks(ds.getId(), sp.getId(), &allocated) < 0) return;  // cannot tell: the reads decide
    if (allocated < expected) {
      throw InputError(where + ": declares " + std::to_string(elements) + " samples, but only " +
                       std::to_string(allocated) + " of its " + std::to_string(expected) +
                       " chunks were ever written (a log preallocated and not filled?)");
    }
  } else if (plist.getLayout() == H5D_CONTIGUOUS && plist.getNfilters() == 0) {
    if (ds.getStorageSize() < elements * ds.getDataType().getSize()) {
      throw InputError(where + ": declares " + std::to_string(elements) + " samples, but its data were never written");
    }
  }
}

}  // namespace

namespace internal {

herr_t DenyExternalLink(const char*, const char*, const char*, const char*, unsigned*, hid_t, void*) {
  return -1;  // an external link would read another file: never followed
}

H5::FileAccPropList SafeH5Access() {
  H5::FileAccPropList fapl;
  H5Pset_elink_cb(fapl.getId(), DenyExternalLink, nullptr);
  return fapl;
}

bool H5LinkExists(hid_t file, const std::string& path, const std::string& name) {
  // Component by component from the root: H5Lexists on "/a/b" would follow a
  // link "/a" into another file; H5Lget_info on each prefix does not.
  if (name.empty() || name[0] != '/') return false;
  std::string prefix;
  size_t start = 1;
  while (start <= name.size()) {
    size_t slash = name.find('/', start);
    if (slash == std::string::npos) slash = name.size();
    if (slash == start) { start = slash + 1; continue; }
    prefix = name.substr(0, slash);
    if (H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    H5L_info_t info;
    if (H5Lget_info(file, prefix.c_str(), &info, H5P_DEFAULT) < 0) return false;
    if (info.type == H5L_TYPE_EXTERNAL || info.type >= H5L_TYPE_UD_MIN) {
      throw InputError(path + ":" + prefix + ": is an external link (to another file); zwidth reads only "
                       "what is inside the file: copy the data into it");
    }
    start = slash + 1;
  }
  return true;
}

bool IsPlainNumber(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  if (cls == H5T_FLOAT) {
    // Only the IEEE single and double layouts: a corrupt file can declare any
    // (mantissa, exponent) split, whose soft conversion libhdf5 does slowly and
    // with buffers sized by that declaration.
    for (hid_t std_type : {H5T_IEEE_F32LE, H5T_IEEE_F32BE, H5T_IEEE_F64LE, H5T_IEEE_F64BE}) {
      if (H5Tequal(type, std_type) > 0) return true;
    }
    return false;
  }
  if (cls == H5T_INTEGER) {
    const size_t size = H5Tget_size(type);
    return (size == 1 || size == 2 || size == 4 || size == 8) && H5Tget_precision(type) == 8 * size &&
           H5Tget_offset(type) == 0;
  }
  return false;
}

// The first filter of a dataset's pipeline that this libhdf5 cannot apply
// (h5py's LZF, 32000; a plugin's), named, or "".
static std::string MissingFilter(hid_t dcpl) {
  const int n = H5Pget_nfilters(dcpl);
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0, config = 0;
    size_t nvalues = 0;
    char name[64] = {};
    const H5Z_filter_t id = H5Pget_filter2(dcpl, static_cast<unsigned>(i), &flags, &nvalues, nullptr, sizeof name,
                                           name, &config);
    if (id < 0 || H5Zfilter_avail(id) > 0) continue;
    const std::string known = id == 32000 ? "LZF (h5py's)" : id == 32001 ? "Blosc" : id == 32004 ? "LZ4" : "";
    return "the HDF5 filter " + std::to_string(id) + " (" + (known.empty() ? std::string(name) : known) + ")";
  }
  return "";
}

void CheckH5DatasetLocal(hid_t dataset, const std::string& where, bool numbers) {
  const hid_t type = H5Dget_type(dataset);
  const bool plain = type >= 0 && IsPlainNumber(type);
  if (type >= 0) H5Tclose(type);
  if (numbers && !plain) {
    throw InputError(where + ": not stored as plain numbers (expected IEEE float32/float64 or 8- to 64-bit "
                     "integers)");
  }
  const hid_t dcpl = H5Dget_create_plist(dataset);
  if (dcpl < 0) throw InputError(where + ": unreadable dataset properties (corrupt file?)");
  const int external = H5Pget_external_count(dcpl);
  const H5D_layout_t layout = H5Pget_layout(dcpl);
  const std::string missing_filter = MissingFilter(dcpl);
  H5Pclose(dcpl);
  if (!missing_filter.empty()) {
    throw InputError(where + ": compressed with " + missing_filter + ", which this HDF5 library does not have: "
                     "save it again with gzip (h5py: compression='gzip') or without compression");
  }
  if (external != 0) {
    throw InputError(where + ": its data are stored in external files; zwidth reads only what is "
                     "inside the file: copy the data into it");
  }
  if (layout == H5D_VIRTUAL) {
    throw InputError(where + ": a virtual dataset (data from other files); copy the data into the file");
  }
}

double ReadH5ScalarAttribute(hid_t object, const std::string& name, const std::string& where) {
  const hid_t a = H5Aopen(object, name.c_str(), H5P_DEFAULT);
  if (a < 0) throw InputError(where + ": attribute " + name + " is unreadable (corrupt file?)");
  const hid_t space = H5Aget_space(a);
  const hid_t type = H5Aget_type(a);
  const hssize_t points = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  double v = 0.0;
  herr_t read = -1;
  const bool plain = type >= 0 && IsPlainNumber(type);
  if (points == 1 && plain) read = H5Aread(a, H5T_NATIVE_DOUBLE, &v);
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  if (points != 1) {
    throw InputError(where + ": attribute " + name + " has " + std::to_string(points) +
                     " values; it must be one number (a scalar)");
  }
  if (!plain) {
    throw InputError(where + ": attribute " + name + " is not a number; it must be one number (a scalar)");
  }
  if (read < 0) throw InputError(where + ": attribute " + name + " is unreadable (corrupt file?)");
  return v;
}

namespace {

// Samples per read and per frame to the parent: 64 kB a buffer, so that the
// buffers come from the heap and are reused. In the forked reader every page
// first touched costs a fault (a copy-on-write one in the inherited heap):
// with 65536-sample buffers (512 kB each, zero-filled) faults were most of
// the child's time, 8-10 ms for the 30 s log against 1.4 ms in process.
constexpr size_t kHdf5Chunk = 8192;

// The datasets of a log, opened and checked (lengths agree, data written),
// and the root attribute sample_rate_hz (0 when absent).
struct Hdf5LogSets {
  H5::DataSet u, y, t;
  bool have_time = false;
  size_t n = 0;
  double attr_rate_hz = 0.0;
};

Hdf5LogSets OpenLogDatasets(H5::H5File& file, const std::string& path, const LogSelect& sel) {
  Hdf5LogSets s;
  s.u = OpenDataset(file, path, sel.input_dataset, "LogSelect::input_dataset");
  s.y = OpenDataset(file, path, sel.output_dataset, "LogSelect::output_dataset");
  s.n = Length1D(s.u, H5Where(path, sel.input_dataset));
  if (Length1D(s.y, H5Where(path, sel.output_dataset)) != s.n) {
    throw InputError(path + ": '" + sel.input_dataset + "' and '" + sel.output_dataset + "' have different lengths");
  }
  if (s.n == 0) throw InputError(path + ": dataset '" + sel.input_dataset + "' is empty");
  CheckWritten(s.u, H5Where(path, sel.input_dataset));
  CheckWritten(s.y, H5Where(path, sel.output_dataset));
  if (file.attrExists("sample_rate_hz")) {
    s.attr_rate_hz = ReadH5ScalarAttribute(file.getId(), "sample_rate_hz", path);
    if (!(s.attr_rate_hz > 0.0) || !std::isfinite(s.attr_rate_hz)) {
      throw InputError(path + ": attribute sample_rate_hz = " + std::to_string(s.attr_rate_hz) +
                       " must be finite and > 0");
    }
  }
  s.have_time = H5LinkExists(file.getId(), path, sel.time_dataset);
  if (s.have_time) {
    s.t = OpenDataset(file, path, sel.time_dataset, "LogSelect::time_dataset");
    if (Length1D(s.t, H5Where(path, sel.time_dataset)) != s.n) {
      throw InputError(path + ": '" + sel.time_dataset + "' has a different length from the signals");
    }
    CheckWritten(s.t, H5Where(path, sel.time_dataset));
  } else if (s.attr_rate_hz <= 0.0 && sel.sample_rate_hz <= 0.0) {
    throw InputError(path + ": neither a '" + sel.time_dataset +
                     "' dataset nor a sample_rate_hz attribute; pass LogSelect::sample_rate_hz");
  }
  return s;
}

// Reads the samples in chunks of kHdf5Chunk, checks them (finite, time increasing
// and uniform, input not constant) and hands each chunk to sink. Returns the
// rate of the time stamps (0 without them). The text of an error is built
// only when there is one (it used to be built for every sample: 5 strings a
// sample, ~60 % of the read's time).
double StreamLogChunks(const Hdf5LogSets& s, const std::string& path, const LogSelect& sel, const LogSink& sink) {
  TimeChecker times(path, sel.max_interval_deviation, sel.sample_rate_hz <= 0.0);  // --rate: only increasing
  ConstantCheck constant;
  const size_t chunk = std::min(kHdf5Chunk, s.n);
  std::vector<double> u(chunk), y(chunk), t(s.have_time ? chunk : 0);
  for (size_t off = 0; off < s.n; off += chunk) {
    const size_t cnt = std::min(chunk, s.n - off);
    ReadSlab(s.u, off, cnt, u.data(), H5Where(path, sel.input_dataset));
    ReadSlab(s.y, off, cnt, y.data(), H5Where(path, sel.output_dataset));
    if (s.have_time) ReadSlab(s.t, off, cnt, t.data(), H5Where(path, sel.time_dataset));
    for (size_t i = 0; i < cnt; ++i) {
      const auto where = [&] { return "sample " + std::to_string(off + i); };
      if (!std::isfinite(u[i]) || !std::isfinite(y[i]) || (s.have_time && !std::isfinite(t[i]))) {
        CheckFinite(u[i], H5Where(path, sel.input_dataset), where());
        CheckFinite(y[i], H5Where(path, sel.output_dataset), where());
        if (s.have_time) CheckFinite(t[i], H5Where(path, sel.time_dataset), where());
      }
      if (s.have_time) times.AddLazy(t[i], [&] { return where() + " of " + sel.time_dataset; });
    }
    constant.Add(u.data(), cnt);
    sink(u.data(), y.data(), cnt);
  }
  if (!constant.varies) {
    throw InputError(path + ": input dataset '" + sel.input_dataset +
                     "' is constant: the log has no excitation to identify from");
  }
  return s.have_time ? times.Rate() : 0.0;
}

// The rate: LogSelect's if given, else the attribute's (which must agree with
// the time stamps within 1 %), else the time stamps'.
double LogRate(const std::string& path, const LogSelect& sel, double attr_rate_hz, double time_rate_hz) {
  double rate = time_rate_hz;
  if (sel.sample_rate_hz > 0.0) {
    rate = sel.sample_rate_hz;
  } else if (attr_rate_hz > 0.0) {
    if (time_rate_hz > 0.0 && std::abs(time_rate_hz - attr_rate_hz) > 0.01 * attr_rate_hz) {
      throw InputError(path + ": attribute sample_rate_hz = " + std::to_string(attr_rate_hz) +
                       " disagrees with the time stamps (" + std::to_string(time_rate_hz) + " Hz)");
    }
    rate = attr_rate_hz;
  }
  if (!(rate > 0.0)) throw InputError(path + ": cannot tell the sample rate; pass LogSelect::sample_rate_hz");
  return rate;
}

}  // namespace

// Why libhdf5 refused to open `path`, for the message: another program holds
// it open for writing (HDF5's file lock), or its writer never closed it (the
// superblock's "open for writing" mark, versions 2 and 3), else truncated or
// corrupt.
static std::string WhyHdf5WontOpen(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::string("cannot open it: ") + std::strerror(errno);
  const bool locked = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  unsigned char sb[12] = {};
  bool open_mark = false;
  for (off_t off : {0, 512, 1024, 2048}) {
    if (::pread(fd, sb, sizeof sb, off) == static_cast<ssize_t>(sizeof sb) && std::memcmp(sb, "\x89HDF\r\n\x1a\n", 8) == 0) {
      open_mark = sb[8] >= 2 && sb[11] != 0;  // superblock version, file consistency flags
      break;
    }
  }
  ::close(fd);
  if (locked) {
    return "another program has it open for writing (HDF5's file lock): wait until it closes the file, or read a "
           "copy";
  }
  if (open_mark) {
    return "the program that wrote it never closed it (it is still being written, or it crashed): when no program "
           "has it open, `h5clear -s FILE` clears the mark; the data may be incomplete";
  }
  return "truncated or corrupt file";
}

LogInfo StreamHdf5InProcess(const std::string& path, const LogSelect& sel, const LogSink& sink) {
  H5::Exception::dontPrint();
  std::unique_ptr<H5::H5File> file;
  try {
    if (!H5::H5File::isHdf5(path)) throw InputError(path + ": not an HDF5 file");
    file = std::make_unique<H5::H5File>(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, SafeH5Access());
  } catch (const H5::Exception&) {
    throw InputError(path + ": cannot open as HDF5 (" + WhyHdf5WontOpen(path) + ")");
  }
  try {
    const Hdf5LogSets sets = OpenLogDatasets(*file, path, sel);
    const double time_rate_hz = StreamLogChunks(sets, path, sel, sink);
    LogInfo info;
    info.source = path;
    info.num_samples = sets.n;
    info.sample_rate_hz = LogRate(path, sel, sets.attr_rate_hz, time_rate_hz);
    return info;
  } catch (const H5::Exception& e) {
    throw InputError(path + ": HDF5 error (" + e.getDetailMsg() + "): truncated or corrupt file?");
  }
}

}  // namespace internal

namespace internal {


namespace {

void WriteStringAttr(H5::H5Object& obj, const std::string& name, const std::string& value) {
  H5::StrType st(H5::PredType::C_S1, value.size() + 1);
  H5::Attribute a = obj.createAttribute(name, st, H5::DataSpace(H5S_SCALAR));
  a.write(st, value.c_str());
  a.close();
}

}  // namespace

void WriteDoubleAttr(H5::H5Object& obj, const std::string& name, double v) {
  H5::Attribute a = obj.createAttribute(name, H5::PredType::IEEE_F64LE, H5::DataSpace(H5S_SCALAR));
  a.write(H5::PredType::NATIVE_DOUBLE, &v);
  a.close();
}

void WriteHdf5Log(const std::string& tmp, double rate, const std::vector<double>& u,
                  const std::vector<double>& y) {
  H5::Exception::dontPrint();
  try {
    H5::H5File file(tmp, H5F_ACC_TRUNC);
    const hsize_t n = u.size();
    H5::DataSpace space(1, &n);
    std::vector<double> t(n);
    for (hsize_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) / rate;
    auto write = [&](H5::Group& parent, const std::string& name, const std::vector<double>& v,
                     const std::string& unit) {
      H5::DataSet ds = parent.createDataSet(name, H5::PredType::IEEE_F64LE, space);
      ds.write(v.data(), H5::PredType::NATIVE_DOUBLE);
      WriteStringAttr(ds, "units", unit);
      ds.close();
    };
    H5::Group root = file.openGroup("/");
    write(root, "time", t, "s");
    H5::Group gi = file.createGroup("/input");
    H5::Group go = file.createGroup("/output");
    write(gi, "torque", u, "N m");
    write(go, "position", y, "rad");
    internal::WriteDoubleAttr(root, "sample_rate_hz", rate);
    WriteStringAttr(root, "sample_rate_units", "Hz");
    // Closed here, inside the try: an error at flush or close (a full disk)
    // must fail the write, not vanish in a destructor.
    gi.close();
    go.close();
    root.close();
    file.flush(H5F_SCOPE_GLOBAL);
    file.close();
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
}

}  // namespace internal
}  // namespace zwidth::io
