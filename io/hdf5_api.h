// The part of io/ that needs libhdf5 or libmatio, behind one table of
// function pointers (internal: not installed, include only from io/*.cc and
// the zwidth executable's plugin loader).
//
// Why: libhdf5 and libmatio bring ~40 shared libraries (curl, krb5, ldap,
// gnutls...) whose loading costs ~14 ms at every process start, and FindHDF5
// needs a C compiler in every project that finds it. So the static library
// zwidth_io holds no HDF5 or MATLAB code: the functions live in zwidth_hdf5
// (target zwidth::hdf5: io/hdf5_api.cc and the readers and writers it lists),
// which installs its table as the provider when it is linked (its link
// interface asks the linker for zwidth_link_hdf5, so its initialiser is kept).
// The zwidth executable installs its own provider instead (apps/plugins.cc):
// it loads the module zwidth-hdf5.so (io/hdf5_plugin.cc, built from that same
// library) on first use, so that the commands that never touch HDF5 or MATLAB
// files never map those libraries. Callers in io/ call Hdf5().<function>(...)
// and do not know which provider they got; with none (a program that links
// zwidth::io without zwidth::hdf5) Hdf5() throws, naming the target to link.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ident/welch.h"
#include "io/log.h"
#include "io/model_json.h"

namespace zwidth::io {
struct BatchTable;  // io/batch_table.h
}  // namespace zwidth::io

namespace zwidth::io::internal {

// The most values a frequency response holds: the bins of a Welch window of
// 2^21 samples (about 35 min at 1 kHz in one window). More is refused before
// it is read, so a small corrupt file cannot become gigabytes.
inline constexpr size_t kMaxFrfBins = size_t{1} << 20;

using LogParser = LogInfo (*)(const std::string& path, const LogSelect& sel, const LogSink& sink);

struct Hdf5Api {
  // Parse a log in this process (RunIsolated runs them in a child):
  // io/log_hdf5.cc's StreamHdf5InProcess, io/log_mat.cc's StreamMatInProcess.
  LogParser stream_hdf5_log = nullptr;
  LogParser stream_mat_log = nullptr;
  // Writers: the temporary file `tmp` of WriteAtomically.
  void (*write_hdf5_log)(const std::string& tmp, double rate, const std::vector<double>& u,
                         const std::vector<double>& y) = nullptr;
  void (*write_frf_hdf5)(const std::string& tmp, const ident::FrequencyResponse& r) = nullptr;
  void (*write_model_hdf5)(const std::string& tmp, const ModelFile& model, double period_s) = nullptr;
  // The .mat model export (io/export_mat.cc): v5 or v7.3; frf may be null.
  void (*write_model_mat)(const std::string& tmp, const ModelFile& model, double period_s,
                          const ident::FrequencyResponse* frf, bool v73) = nullptr;
  // Frequency-response file (io/frf_h5.cc): n, 4 scalars and 7 columns packed
  // as doubles; whether the file has a /frf group (false if unreadable).
  std::string (*read_frf_hdf5_packed)(const std::string& path) = nullptr;
  bool (*has_frf_group)(const std::string& path) = nullptr;
  // A response in a .mat file (io/frf_mat.cc), packed as read_frf_hdf5_packed
  // with NaN for an absent coherence or H_std column; whether a .mat file
  // holds f and H (or H_re) variables.
  std::string (*read_frf_mat_packed)(const std::string& path) = nullptr;
  bool (*has_frf_mat_variables)(const std::string& path) = nullptr;
  // The batch table (io/batch_table_h5.cc): written to `tmp`; read back as
  // FormatBatchCsv's text (a child sends it to the parent).
  void (*write_batch_table_hdf5)(const std::string& tmp, const BatchTable& table) = nullptr;
  std::string (*read_batch_table_hdf5)(const std::string& path) = nullptr;
  // HDF5 files, datasets, groups and attributes open now (H5Fget_obj_count).
  long (*open_objects)() = nullptr;
};

// Changes whenever a type crossing the table changes size; the executable and
// the plugin also mix in ZWIDTH_ABI_HASH, the hash of the shared headers
// (cmake/abi_hash.cmake): the executable refuses a plugin built from other
// headers (a stale or foreign file) even when every size is the same.
inline constexpr unsigned long long kHdf5ApiKey =
    (1ull << 56) ^ (sizeof(Hdf5Api) << 40) ^ (sizeof(LogSelect) << 28) ^ (sizeof(LogInfo) << 20) ^
    (sizeof(ident::FrequencyResponse) << 8) ^ sizeof(ModelFile);

// Where Hdf5() gets its table: zwidth::hdf5's LinkedHdf5, or the executable's
// plugin loader (a missing or broken plugin is a ComputationError naming the
// file). The latest call wins; set before main, by static initialisers.
using Hdf5Provider = const Hdf5Api& (*)();
void SetHdf5Provider(Hdf5Provider provider);

// The provider's table (io/hdf5_provider.cc, in zwidth_io). Without a provider,
// a ComputationError that says to link zwidth::hdf5.
const Hdf5Api& Hdf5();

// The table of the real functions, linked into this binary (io/hdf5_api.cc,
// in zwidth_hdf5; the plugin's entry point returns it).
const Hdf5Api& LinkedHdf5();

// The one way io/ writes an HDF5 or MATLAB file: WriteAtomically(path), with
// write(Hdf5(), tmp) called under LibraryForkMutex() (libhdf5's global lock
// must not be held across a fork, io/isolated.h). An HDF5 writer whose file or
// objects failed to close (a full disk at the final flush: the C++ API
// swallows that error in its destructors) leaves them open; such a file is
// corrupt, so it is an InputError and never renamed into place (and the
// process then ends before libhdf5's exit handler, which would crash on it).
void WriteHdf5Atomically(const std::string& path,
                         const std::function<void(const Hdf5Api& h5, const std::string& tmp)>& write);

// The real functions behind the table (they need HDF5/matio headers and libraries).
LogInfo StreamMatInProcess(const std::string& path, const LogSelect& sel, const LogSink& sink);  // log_mat.cc
void WriteFrfHdf5(const std::string& tmp, const ident::FrequencyResponse& r);                   // frf_h5.cc
std::string ReadFrfHdf5Packed(const std::string& path);                                          // frf_h5.cc
bool HasFrfGroup(const std::string& path);                                                       // frf_h5.cc
void WriteModelHdf5(const std::string& tmp, const ModelFile& model, double period_s);            // export_h5.cc
void WriteModelMat(const std::string& tmp, const ModelFile& model, double period_s,
                   const ident::FrequencyResponse* frf, bool v73);                               // export_mat.cc
std::string ReadFrfMatPacked(const std::string& path);                                           // frf_mat.cc
bool HasFrfMatVariables(const std::string& path);                                                // frf_mat.cc
void WriteBatchTableHdf5(const std::string& tmp, const BatchTable& table);                      // batch_table_h5.cc
std::string ReadBatchTableHdf5(const std::string& path);                                         // batch_table_h5.cc

}  // namespace zwidth::io::internal
