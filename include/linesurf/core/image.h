#pragma once
/// A simple RGBA float image, row-major, origin at the top-left.
#include <cstddef>
#include <vector>

#include "linesurf/core/math.h"

namespace linesurf {

struct Image {
  int width = 0, height = 0;
  std::vector<Color> pixels;  ///< width * height, linear RGBA in [0,1]

  Image() = default;
  Image(int w, int h, Color fill = Color(0, 0, 0, 0)) : width(w), height(h), pixels(size_t(w) * h, fill) {}
  Color& at(int x, int y) { return pixels[size_t(y) * width + x]; }
  const Color& at(int x, int y) const { return pixels[size_t(y) * width + x]; }
  bool empty() const { return pixels.empty(); }
  /// Bilinear lookup with wrap-around addressing; (u, v) in texture space, v = 0 at the bottom
  /// row (OpenGL/OBJ convention).
  Color sampleBilinear(float u, float v) const;
};

}  // namespace linesurf
