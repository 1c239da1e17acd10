#include "linesurf/core/budget.h"

#include <fmt/format.h>

#include <cmath>

#include "linesurf/core/error.h"

namespace linesurf {

Budget::Budget(double megabytes, std::string name) : megabytes_(megabytes), name_(std::move(name)) {
  if (!(megabytes > 0) || !std::isfinite(megabytes))
    throwBadParameter(name_, fmt::format("must be a finite number of MiB > 0, got {:g}", megabytes));
}

void Budget::require(std::string_view option, double bytes, std::string_view what) const {
  if (allows(bytes)) return;
  throwBadParameter(std::string(option),
                    fmt::format("{} needs about {:.3g} MiB, more than {} {:g} (raise {} to allow it)", what,
                                bytes / (1024.0 * 1024.0), name_, megabytes_, name_));
}

double renderViewBytes(int width, int height, int layers) {
  return double(width) * double(height) * (16.0 * 4 + 48.0 * std::max(layers, 1));
}

double pngFileBytes(int width, int height) { return double(width) * double(height) * 4.0 + 1024.0; }

double modelFileBytes(size_t points, size_t segments, bool text) {
  // Binary rows: position, normal, colour, radius (32 bytes a point); segment rows twice that.
  // Text: about 16 characters a number.
  return text ? double(points) * 16.0 * 8 + double(segments) * 16.0 * 14 + 4096.0
              : double(points) * 32.0 + double(segments) * 64.0 + 4096.0;
}

double pointGeometryBytes(size_t points, int k) {
  // Neighbour indices and distances (8 bytes each per neighbour), the model's points (~64 bytes),
  // normals, radii, flags and the kd-tree (~64 bytes a point).
  return double(points) * (8.0 * std::max(k, 1) + 128.0);
}

}  // namespace linesurf
