// The zwidth executable's provider of io::internal::Hdf5() and its own fit::FitLibrary()
// (io/hdf5_api.h, fit/fit_api.h): the HDF5/MATLAB code and the fit are loaded
// from the plugins zwidth-hdf5.so and zwidth-fit.so on first use, so that a
// command that needs neither (--help, boundary, relay, check, compare on JSON
// models...) does not map libhdf5, libmatio, Ceres and the ~50 libraries they
// bring. Measured on the development machine (perf stat -r 30): `zwidth --help`
// took 24 ms with all of them linked.
//
// The plugins are found at a path fixed at build time relative to the real
// path of this executable (/proc/self/exe): <bindir>/ZWIDTH_PLUGIN_DIR_FROM_BIN/,
// never from an environment variable, the working folder or a flag. They are
// loaded RTLD_NOW | RTLD_LOCAL (every symbol resolved now, none visible to
// other code). A missing or broken plugin is a ComputationError (exit 1) that
// names the file and says to reinstall.
#include <dlfcn.h>
#include <limits.h>
#include <unistd.h>

#include <mutex>
#include <string>

#include "fit/fit_api.h"
#include "ident/fft.h"
#include "io/hdf5_api.h"
#include "model/error.h"
#include "zwidth_abi_hash.h"  // generated (cmake/abi_hash.cmake): the shared headers' hash

#ifndef ZWIDTH_PLUGIN_DIR_FROM_BIN
#error "ZWIDTH_PLUGIN_DIR_FROM_BIN (the plugins' folder relative to the executable's) is set by apps/CMakeLists.txt"
#endif

namespace zwidth {
namespace {

std::string PluginPath(const char* file) {
  char exe[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) {
    throw ComputationError(std::string("cannot find the zwidth executable's folder (/proc/self/exe), where the "
                                       "plugin ") + file + " is looked for; is /proc mounted?");
  }
  std::string dir(exe, static_cast<size_t>(n));
  dir.erase(dir.rfind('/') + 1);
  return dir + ZWIDTH_PLUGIN_DIR_FROM_BIN + "/" + file;
}

// Loads `file` and returns what its entry point `symbol`(key) gives.
const void* LoadPlugin(const char* file, const char* symbol, unsigned long long key, const char* what) {
  const std::string path = PluginPath(file);
  const std::string reinstall = std::string(" (zwidth needs it for ") + what +
                                "): this zwidth installation is incomplete or broken; reinstall zwidth";
  void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    std::string why = ::dlerror() ?: "unknown error";
    if (why.rfind(path + ": ", 0) == 0) why.erase(0, path.size() + 2);  // dlerror() repeats the path
    throw ComputationError("cannot load the plugin " + path + " (" + why + ")" + reinstall);
  }
  using Entry = const void* (*)(unsigned long long);
  const auto entry = reinterpret_cast<Entry>(::dlsym(handle, symbol));
  const void* api = entry ? entry(key) : nullptr;
  if (!api) {  // not dlclose()d: what its initialisers allocated stays reachable (LeakSanitizer)
    throw ComputationError("the plugin " + path + (entry ? " was built from another version of zwidth"
                                                         : std::string(" has no entry point ") + symbol) +
                           reinstall);
  }
  return api;  // the handle stays open for the process's life
}

// The loaded table, once; a failed load throws and is retried on the next
// call. `bind` runs on the new table before any other thread sees it.
template <class Api, class Bind>
const Api& Loaded(const Api*& api, std::mutex& mutex, const char* file, const char* symbol,
                  unsigned long long key, const char* what, Bind bind) {
  std::lock_guard<std::mutex> lock(mutex);
  if (!api) {
    const Api* loaded = static_cast<const Api*>(LoadPlugin(file, symbol, key, what));
    bind(*loaded);
    api = loaded;
  }
  return *api;
}

const io::internal::Hdf5Api* g_hdf5 = nullptr;
std::mutex g_hdf5_mutex;
const fit::FitApi* g_fit = nullptr;
std::mutex g_fit_mutex;

}  // namespace

namespace io::internal {
namespace {

const Hdf5Api& LoadedHdf5() {
  return Loaded(g_hdf5, g_hdf5_mutex, "zwidth-hdf5.so", "zwidth_hdf5_plugin", kHdf5ApiKey ^ ZWIDTH_ABI_HASH,
                "HDF5 and MATLAB files", [](const Hdf5Api&) {});
}
// Hdf5()'s table (io/hdf5_api.h) is the plugin's, loaded on first call.
const bool kProvided = (SetHdf5Provider(&LoadedHdf5), true);

}  // namespace
}  // namespace io::internal

namespace fit {

const FitApi& FitLibrary() {
  // The plugin's copy of ident/ plans FFTW (the friction fit) under this
  // executable's lock, the one Welch's plans take (ident/fft.h).
  return Loaded(g_fit, g_fit_mutex, "zwidth-fit.so", "zwidth_fit_plugin", kFitApiKey ^ ZWIDTH_ABI_HASH, "fitting a model",
                [](const FitApi& a) { a.share_fftw_planner_mutex(&ident::FftwPlannerMutex()); });
}

}  // namespace fit
}  // namespace zwidth
