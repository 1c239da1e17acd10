// libFuzzer target for the OBJ reader (strict pre-scan + tinyobjloader + index checks) and the
// mesh validation after reading; see ply_fuzz.cpp for what counts as a finding.
#include <cstdint>
#include <string_view>

#include "fuzz_common.h"
#include "linesurf/io/model_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    fuzz::checkMesh(linesurf::readObjMeshFromMemory(bytes, "fuzz.obj"));
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
  }
  return 0;
}
