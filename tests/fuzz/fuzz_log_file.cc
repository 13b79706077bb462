// libFuzzer target: a reader on arbitrary bytes must refuse bad input with an
// InputError, never crash, hang or leak. Built five times (CMakeLists.txt):
//   ".csv"                    the CSV log reader (ReadLog);
//   ".h5"                     the HDF5 log reader, in process (the child's code);
//   ".h5"  + ZWIDTH_FUZZ_FRF  the HDF5 frequency-response reader, in process;
//   ".csv" + ZWIDTH_FUZZ_FRF  the frequency-response CSV reader;
//   ".json"+ ZWIDTH_FUZZ_SCENE the haptic-scene reader (ReadScene).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

#include <hdf5.h>

#include "io/frf_file.h"
#include "io/frf_file_internal.h"
#include "io/log.h"
#include "io/log_internal.h"
#include "io/stability_files.h"
#include "model/error.h"

// libhdf5 keeps a corrupt file whose close failed open, and crashes on it in
// its exit handler (H5F__close_cb, from H5close at exit). zwidth's reader child
// leaves with _exit() and never runs that handler; the fuzzer does the same
// (registered after libhdf5's, so it runs first). Inputs are still checked
// one by one, and libFuzzer's own leak checks run during the run.
void SkipHdf5AtExit() { ::_exit(0); }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool registered = [] {
    H5open();
    return std::atexit(SkipHdf5AtExit) == 0;
  }();
  (void)registered;
  static const std::string path = "/tmp/zwidth_fuzz_" + std::to_string(getpid()) + ZWIDTH_FUZZ_EXT;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
#if defined(ZWIDTH_FUZZ_SCENE)
    zwidth::io::ReadScene(path);
#elif defined(ZWIDTH_FUZZ_FRF)
    zwidth::io::internal::ReadFrequencyResponseInProcess(path, 0.0);
#else
    const std::string ext = ZWIDTH_FUZZ_EXT;
    if (ext == ".h5") {
      zwidth::io::internal::StreamHdf5InProcess(path, {}, [](const double*, const double*, size_t) {});
    } else {
      zwidth::io::ReadLog(path);
    }
#endif
  } catch (const zwidth::InputError&) {
  }
  return 0;
}
