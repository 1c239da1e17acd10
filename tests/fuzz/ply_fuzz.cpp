// libFuzzer target for the PLY reader (both the model and the mesh mapping) and the model
// validation after reading. Bad input must end in linesurf::Error with a one-line message;
// anything else (crash, other exception, huge allocation, hang) is a finding. Run with
// scripts/fuzz.sh SECS.
#include <cstdint>
#include <string_view>

#include "fuzz_common.h"
#include "linesurf/io/model_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    fuzz::checkModel(linesurf::readPlyModelFromMemory(bytes, "fuzz.ply"));
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
  }
  try {
    fuzz::checkMesh(linesurf::readPlyMeshFromMemory(bytes, "fuzz.ply"));
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
  }
  return 0;
}
