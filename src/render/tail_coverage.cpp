// Tail coverage (beyond the thesis; tail_coverage.h).
#include "tail_coverage.h"

namespace linesurf::detail {

void compositeTailPixels(const std::vector<std::vector<TailPixel>>& tailPixels, size_t tiles, const uint8_t* covered,
                         const Color& background, Image& color, Image* alpha) {
  const int w = color.width, h = color.height;
  auto bordersEmpty = [&](int x, int y) {
    for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy)
      for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx)
        if (!covered[size_t(yy) * size_t(w) + size_t(xx)]) return true;
    return false;
  };
  for (size_t tile = 0; tile < tiles; ++tile)
    for (const TailPixel& t : tailPixels[tile]) {
      const int x = int(t.x), y = int(t.y);
      if (!bordersEmpty(x, y)) continue;
      Color& c = color.at(x, y);  // written opaque: its straight colour
      const float a = t.alpha;
      c = overBackground(Color(a * c.x(), a * c.y(), a * c.z(), a), background);
      if (alpha) alpha->at(x, y) = Color(a, a, a, a);
    }
}

}  // namespace linesurf::detail
