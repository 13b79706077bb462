// Hdf5() of zwidth_io: whichever table was provided (io/hdf5_api.h), and the
// open-object check of every HDF5 or MATLAB write. Nothing here links libhdf5:
// a program that reads a model JSON links neither libhdf5 nor libmatio.
#include <atomic>
#include <cerrno>
#include <filesystem>
#include <cstdio>
#include <cstdlib>
#include <mutex>

#include <sys/statvfs.h>
#include <unistd.h>

#include "io/atomic_file.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "io/isolated.h"
#include "model/error.h"

namespace zwidth::io::internal {
namespace {

std::atomic<Hdf5Provider> g_provider{nullptr};

// An HDF5 file whose close failed (a full disk) stays open inside libhdf5,
// which retries at exit and crashes (SIGSEGV instead of exit 2; closing it
// again crashes the same way). So once that happened, the process ends with
// the exit code of an InputError before libhdf5's exit handler runs (atexit
// handlers run in reverse order of registration, this one is the latest).
void ExitBeforeHdf5Cleanup() {
  std::fflush(nullptr);
  ::_exit(2);
}

}  // namespace

void SetHdf5Provider(Hdf5Provider provider) { g_provider.store(provider); }

const Hdf5Api& Hdf5() {
  const Hdf5Provider provider = g_provider.load();
  if (provider == nullptr) {
    throw ComputationError(
        "HDF5 and MATLAB (.h5, .mat) files need the library zwidth::hdf5, which this program does not link: "
        "find_package(zwidth COMPONENTS hdf5) and target_link_libraries(<target> PRIVATE zwidth::hdf5) "
        "(or use text logs and JSON models)");
  }
  return provider();
}

void WriteHdf5Atomically(const std::string& path,
                         const std::function<void(const Hdf5Api& h5, const std::string& tmp)>& write) {
  const Hdf5Api& h5 = Hdf5();  // loaded before the temporary file exists
  WriteAtomically(path, [&](const std::string& tmp) {
    std::lock_guard<std::recursive_mutex> hold(LibraryForkMutex());
    const long open_before = h5.open_objects();
    try {
      write(h5, tmp);
    } catch (const InputError&) {
      // HDF5 says "H5Dwrite failed" about the temporary; a full disk is said as a text file's is
      // (the user's name, the system's reason), found by errno or by no free block left.
      const int err = errno;
      struct statvfs fs;
      const std::string folder = std::filesystem::path(tmp).parent_path().string();
      const bool full = err == ENOSPC || err == EDQUOT ||
                        (::statvfs(folder.empty() ? "." : folder.c_str(), &fs) == 0 && fs.f_bavail == 0);
      if (full) throw InputError(WriteFailure(tmp, ENOSPC));
      throw;
    }
    if (h5.open_objects() > open_before) {
      static std::once_flag once;
      std::call_once(once, [] { std::atexit(ExitBeforeHdf5Cleanup); });
      throw InputError("failed writing '" + path + "': the HDF5 library could not close the file "
                       "(disk full?); nothing was written");
    }
  });
}

}  // namespace zwidth::io::internal
