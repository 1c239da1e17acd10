// A drawing as SVG (render/drawing.h): the runs that the raster draws, one path each, so that the
// vector and the raster output show the same strokes.
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "linesurf/render/drawing.h"

namespace linesurf {
namespace {

std::string hexColor(const Color& c) {
  auto byte = [](float v) { return int(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  return fmt::format("#{:02x}{:02x}{:02x}", byte(c.x()), byte(c.y()), byte(c.z()));
}

}  // namespace

std::string drawingSvg(const Drawing& d, const DrawingOptions& o) {
  const int w = d.image.width, h = d.image.height;
  std::string s;
  s.reserve(64 * d.runs.size() + 512);
  s += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  s += fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\">\n", w, h, w, h);
  if (o.paper.w() > 0)
    s += fmt::format("<rect width=\"{}\" height=\"{}\" fill=\"{}\"{}/>\n", w, h, hexColor(o.paper),
                     o.paper.w() < 1 ? fmt::format(" fill-opacity=\"{:g}\"", o.paper.w()) : "");
  s += fmt::format("<g fill=\"none\" stroke=\"{}\" stroke-width=\"{:g}\" stroke-linecap=\"round\" stroke-linejoin=\"round\"{}>\n",
                   hexColor(o.ink), o.strokeWidth, o.ink.w() < 1 ? fmt::format(" stroke-opacity=\"{:g}\"", o.ink.w()) : "");
  for (const StrokeRun& r : d.runs) {
    s += "<path d=\"";
    for (size_t i = 0; i < r.points.size(); ++i)
      s += fmt::format("{}{:.2f} {:.2f}", i == 0 ? "M" : " L", r.points[i].x(), r.points[i].y());
    s += "\"/>\n";
  }
  s += "</g>\n</svg>\n";
  return s;
}

}  // namespace linesurf
