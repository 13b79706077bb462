// libFuzzer target: the model JSON reader.
#include <cstdint>
#include <string>

#include "io/model_json.h"
#include "model/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    zwidth::io::ParseModelJson(std::string(reinterpret_cast<const char*>(data), size), "fuzz");
  } catch (const zwidth::InputError&) {
  }
  return 0;
}
