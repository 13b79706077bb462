// libFuzzer target: a reader on arbitrary bytes must refuse bad input with an
// InputError, never crash, hang or leak. Built five times (CMakeLists.txt):
//   ".csv"                    the CSV log reader (ReadLog);
//   ".h5"                     the HDF5 log reader, in process (the child's code);
//   ".h5"  + ZWIDTH_FUZZ_FRF  the HDF5 frequency-response reader, in process;
//   ".csv" + ZWIDTH_FUZZ_FRF  the frequency-response CSV reader;
//   ".json"+ ZWIDTH_FUZZ_SCENE the haptic-scene reader (ReadScene).
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

#include "io/frf_file.h"
#include "io/log.h"
#include "io/stability_files.h"
#include "model/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
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
