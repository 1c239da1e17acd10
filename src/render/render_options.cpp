// Validation of the pipeline's options (render_options.h).
#include "linesurf/render/render_options.h"

#include <cmath>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"

namespace linesurf {

namespace {
bool inRange(float v, float lo, float hi) { return std::isfinite(v) && v >= lo && v <= hi; }
}  // namespace

void validate(const RenderOptions& o) {
  if (!inRange(o.prefilterVariance, 0, 100)) throwBadOption("prefilterVariance", "must be in [0, 100] pixels^2");
  if (!inRange(o.cutoffRadius, 1, 5)) throwBadOption("cutoffRadius", "must be in [1, 5] standard deviations");
  if (!(o.reconstructionScale > 0 && o.reconstructionScale <= 4))
    throwBadOption("reconstructionScale", "must be in (0, 4]");
  if (o.zThreshold && !inRange(*o.zThreshold, 0, 1e6)) throwBadOption("zThreshold", "must be finite and >= 0");
  if (o.layers < 1 || o.layers > RenderOptions::kMaxLayers)
    throwBadOption("layers", "must be in [1, " + std::to_string(RenderOptions::kMaxLayers) + "]");
  const Material& m = o.material;
  if (!inRange(m.ambient, 0, 1)) throwBadOption("ambient", "must be in [0, 1]");
  if (!inRange(m.diffuse, 0, 1)) throwBadOption("diffuse", "must be in [0, 1]");
  if (!inRange(m.specular, 0, 1)) throwBadOption("specular", "must be in [0, 1]");
  if (!inRange(m.shininess, 1e-3f, 1e4f)) throwBadOption("shininess", "must be in (0, 10000]");
  if (!o.light.direction.allFinite() || o.light.direction.norm() == 0)
    throwBadOption("light", "must be a finite non-zero vector");
  if (!o.light.color.allFinite() || (o.light.color.array() < 0).any())
    throwBadOption("lightColor", "must be finite and >= 0");
  if (!o.defaultColor.allFinite() || (o.defaultColor.array() < 0).any() || (o.defaultColor.array() > 1).any())
    throwBadOption("defaultColor", "channels must be in [0, 1]");
  if (!o.background.allFinite() || (o.background.array() < 0).any() || (o.background.array() > 1).any())
    throwBadOption("background", "channels must be in [0, 1]");
  if (!(std::isfinite(o.alphaOverride) && o.alphaOverride <= 1))
    throwBadOption("alphaOverride", "must be in [0, 1] (or negative to keep the model's alpha)");
  if (!inRange(o.segmentLod, 0, 4))
    throwBadOption("segmentLod", "must be in [0, 4] kernel standard deviations (0 = every segment exact)");
  if (!inRange(o.coverageGain, 0, 100)) throwBadOption("coverageGain", "must be in [0, 100] (0 = off)");
  if (!inRange(o.tailCoverage, 0, 100)) throwBadOption("tailCoverage", "must be in [0, 100] (0 = off)");
  if (o.coverageReach < 0 || o.coverageReach > 16) throwBadOption("coverageReach", "must be in [0, 16] pixels (0 = everywhere)");
  if (o.tileSize < 8 || o.tileSize > 1024) throwBadOption("tileSize", "must be in [8, 1024] pixels");
}

}  // namespace linesurf
