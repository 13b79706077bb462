// libFuzzer target: a log reader on arbitrary bytes must refuse bad input with
// an InputError, never crash, hang or leak. Built three times (CMakeLists.txt):
// with ZWIDTH_FUZZ_EXT ".csv" for the CSV reader, ".h5" for the HDF5 reader,
// and ".h5" with ZWIDTH_FUZZ_FRF for the HDF5 frequency-response reader.
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

#include "io/frf_file.h"
#include "io/log.h"
#include "model/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/tmp/zwidth_fuzz_" + std::to_string(getpid()) + ZWIDTH_FUZZ_EXT;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
#ifdef ZWIDTH_FUZZ_FRF
    zwidth::io::ReadFrequencyResponse(path);
#else
    zwidth::io::ReadLog(path);
#endif
  } catch (const zwidth::InputError&) {
  }
  return 0;
}
