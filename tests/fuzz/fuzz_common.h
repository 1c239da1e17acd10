#pragma once
// Shared checks of the libFuzzer targets: bad input must end in linesurf::Error with a one-line
// message; whatever a reader accepts must satisfy the model validation (it already ran inside
// the reader, so this re-checks that no reader skips it).
#include <cstdlib>
#include <string_view>

#include "linesurf/core/error.h"
#include "linesurf/io/model_validate.h"

namespace fuzz {

inline void checkMessage(const linesurf::Error& e) {
  const std::string_view m(e.what());
  if (m.find('\n') != std::string_view::npos || m.find('\0') != std::string_view::npos) std::abort();  // one line
  if (m.empty()) std::abort();
}

inline void checkModel(const linesurf::HybridModel& m) {
  for (const auto& [name, values] : m.pointProperties)
    if (values.size() != m.points.size()) std::abort();
  try {
    linesurf::validateModel(m, "fuzz");
  } catch (const linesurf::Error&) {
    std::abort();  // a reader returned a model its own validation refuses
  }
}

inline void checkMesh(const linesurf::TriangleMesh& m) {
  for (const auto& f : m.faces)
    for (uint32_t v : f)
      if (v >= m.positions.size()) std::abort();  // the reader promised valid indices
  if (!m.cornerUVs.empty() && m.cornerUVs.size() != m.faces.size()) std::abort();
  try {
    linesurf::validateMesh(m, "fuzz");
  } catch (const linesurf::Error&) {
    std::abort();
  }
}

}  // namespace fuzz
