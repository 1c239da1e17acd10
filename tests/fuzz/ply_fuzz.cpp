// libFuzzer target for the PLY reader (both the model and the mesh mapping). Bad input must end
// in linesurf::Error with a one-line message; anything else (crash, other exception, huge
// allocation, hang) is a finding. Run with scripts/fuzz.sh SECS.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "linesurf/core/error.h"
#include "linesurf/io/model_io.h"

namespace {
void checkMessage(const linesurf::Error& e) {
  if (std::string_view(e.what()).find('\n') != std::string_view::npos) std::abort();  // must be one line
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    linesurf::HybridModel m = linesurf::readPlyModelFromMemory(bytes, "fuzz.ply");
    for (const auto& [name, values] : m.pointProperties)
      if (values.size() != m.points.size()) std::abort();
  } catch (const linesurf::Error& e) {
    checkMessage(e);
  }
  try {
    linesurf::TriangleMesh m = linesurf::readPlyMeshFromMemory(bytes, "fuzz.ply");
    for (const auto& f : m.faces)
      for (uint32_t v : f)
        if (v >= m.positions.size()) std::abort();  // the reader promised valid indices
    if (!m.cornerUVs.empty() && m.cornerUVs.size() != m.faces.size()) std::abort();
  } catch (const linesurf::Error& e) {
    checkMessage(e);
  }
  return 0;
}
