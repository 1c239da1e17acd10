#pragma once
/// A visible part of a drawing's stroke (thesis §9.4, §9.5; render/drawing.h), as the raster
/// draws it and the SVG writer writes it.
#include <cstdint>
#include <vector>

#include "linesurf/core/math.h"

namespace linesurf {

/// A visible part of a stroke in screen pixels (x right, y down).
struct StrokeRun {
  uint32_t stroke = 0;  ///< StrokeSet index; silhouettes: kSilhouette
  std::vector<Vec2f> points;
  static constexpr uint32_t kSilhouette = 0xffffffffu;
};

}  // namespace linesurf
