// libFuzzer target for the LAS reader and the model validation after reading; see ply_fuzz.cpp.
// Whatever the reader accepts must also write back as LAS and read again with as many points.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "fuzz_common.h"
#include "linesurf/io/las_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const linesurf::HybridModel m = linesurf::readLasModelFromMemory(bytes, "fuzz.las");
    fuzz::checkModel(m);
    const std::string again = linesurf::lasBytes(m, {}, "fuzz-out.las");
    if (linesurf::readLasModelFromMemory(again, "fuzz-out.las").points.size() != m.points.size()) std::abort();
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
  }
  return 0;
}
