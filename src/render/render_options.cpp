// Validation of the pipeline's options (render_options.h).
#include "linesurf/render/render_options.h"

#include <cmath>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"

namespace linesurf {

// The ranges are those of the option table (pipeline/option_tables.h); tests/options checks the
// two agree for every field with hostile values.
void validate(const RenderOptions& o) {
  requireRange("prefilterVariance", o.prefilterVariance, 0, 100, "pixels^2");
  requireRange("cutoffRadius", o.cutoffRadius, 1, 5, "standard deviations");
  // Below 0.01 the reconstruction kernel is cut by the stretch limit in every view: nothing is drawn.
  requireRange("reconstructionScale", o.reconstructionScale, 0.01, 4);
  if (o.zThreshold) requireRange("zThreshold", *o.zThreshold, 0, 1e6);
  requireRange("layers", o.layers, 1, RenderOptions::kMaxLayers);
  const Material& m = o.material;
  requireRange("ambient", m.ambient, 0, 1);
  requireRange("diffuse", m.diffuse, 0, 1);
  requireRange("specular", m.specular, 0, 1);
  requireRange("shininess", m.shininess, 1e-3, 1e4);
  if (!o.light.direction.allFinite() || o.light.direction.norm() == 0)
    throwBadOption("light", "must be a finite non-zero vector");
  if (!o.light.color.allFinite() || (o.light.color.array() < 0).any())
    throwBadOption("lightColor", "must be finite and >= 0");
  if (!o.defaultColor.allFinite() || (o.defaultColor.array() < 0).any() || (o.defaultColor.array() > 1).any())
    throwBadOption("defaultColor", "channels must be in [0, 1]");
  if (!o.background.allFinite() || (o.background.array() < 0).any() || (o.background.array() > 1).any())
    throwBadOption("background", "channels must be in [0, 1]");
  if (o.alphaOverride != -1.0f && !(o.alphaOverride >= 0 && o.alphaOverride <= 1))
    throwBadOption("alphaOverride", "must be in [0, 1] (or -1, the default: the model's alpha), got " + numberText(o.alphaOverride));
  requireRange("segmentLod", o.segmentLod, 0, 4, "kernel standard deviations (0 = every segment exact)");
  requireRange("coverageGain", o.coverageGain, 0, 100);
  requireRange("tailCoverage", o.tailCoverage, 0, 100);
  requireRange("coverageReach", o.coverageReach, 0, 16, "pixels (0 = everywhere)");
  requireRange("tileSize", o.tileSize, 8, 1024, "pixels");
}


}  // namespace linesurf
