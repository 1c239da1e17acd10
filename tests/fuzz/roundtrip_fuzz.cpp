// libFuzzer target for "a writer never writes what the readers refuse": whatever the PLY, OBJ or
// XYZ reader accepts (the first byte picks the reader, the rest is the file) is written as
// binary PLY, ascii PLY and (points only) XYZ, and each must read back with the same counts.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "fuzz_common.h"
#include "linesurf/io/model_io.h"

namespace {
const std::filesystem::path& dir() {
  static const std::filesystem::path d = [] {
    auto p = std::filesystem::temp_directory_path() / ("linesurf_roundtrip_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    return p;
  }();
  return d;
}

void roundTrip(const linesurf::HybridModel& m) {
  using namespace linesurf;
  for (PlyEncoding enc : {PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii}) {
    const auto path = dir() / "m.ply";
    try {
      writeModel(path, m, WriteOptions{enc});
    } catch (const Error& e) {
      fuzz::checkMessage(e);
      continue;  // refused to write: fine, as long as it says so in one line
    }
    HybridModel back = readModel(path);  // must not throw: the writer wrote it
    if (back.points.size() != m.points.size() || back.segments.size() != m.segments.size()) std::abort();
  }
  if (m.segments.empty()) {
    const auto path = dir() / "m.xyz";
    try {
      writeModel(path, m);
    } catch (const Error& e) {
      fuzz::checkMessage(e);
      return;
    }
    if (readModel(path).points.size() != m.points.size()) std::abort();
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  linesurf::HybridModel m;
  try {
    switch (data[0] % 3) {
      case 0: m = linesurf::readPlyModelFromMemory(bytes, "fuzz.ply"); break;
      case 1: m = linesurf::readXyzModelFromMemory(bytes, "fuzz.xyz"); break;
      default: {
        linesurf::TriangleMesh mesh = linesurf::readObjMeshFromMemory(bytes, "fuzz.obj");
        m.points.resize(mesh.positions.size());
        for (size_t i = 0; i < mesh.positions.size(); ++i) m.points[i].position = mesh.positions[i];
      }
    }
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
    return 0;
  }
  try {
    roundTrip(m);
  } catch (const linesurf::Error& e) {
    std::abort();  // a reader refused what a writer wrote
  }
  return 0;
}
