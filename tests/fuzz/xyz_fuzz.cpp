// libFuzzer target for the XYZ reader and the model validation after reading; see ply_fuzz.cpp.
#include <cstdint>
#include <string_view>

#include "fuzz_common.h"
#include "linesurf/io/model_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    fuzz::checkModel(linesurf::readXyzModelFromMemory(bytes, "fuzz.xyz"));
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
  }
  return 0;
}
