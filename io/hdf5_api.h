// The part of io/ that needs libhdf5 or libmatio, behind one table of
// function pointers (internal: not installed, include only from io/*.cc and
// the zwidth executable's plugin loader).
//
// Why: libhdf5 and libmatio bring ~40 shared libraries (curl, krb5, ldap,
// gnutls...) whose loading costs ~14 ms at every process start. The static
// library zwidth_io defines Hdf5() in io/hdf5_api.cc as the table of the real
// functions (find_package(zwidth) users and the Python module get exactly that).
// The zwidth executable defines Hdf5() itself (apps/plugins.cc): it loads the
// module zwidth-hdf5.so (io/hdf5_plugin.cc, built from this same library) on
// first use, so that the commands that never touch HDF5 or MATLAB files never
// map those libraries. Callers in io/ call Hdf5().<function>(...) and do not
// know which of the two they got.
#pragma once

#include <string>
#include <vector>

#include "ident/welch.h"
#include "io/log.h"
#include "io/model_json.h"

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

// The table: the real functions (zwidth_io), or the plugin's, loaded on first
// call (the zwidth executable; a missing or broken plugin is a
// ComputationError naming the file).
const Hdf5Api& Hdf5();

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

// HDF5 objects open now, without loading anything: 0 while libhdf5 is not
// loaded (then nothing can be open).
long Hdf5OpenObjects();

}  // namespace zwidth::io::internal
