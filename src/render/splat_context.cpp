// Per-frame constants, option validation and Phong lighting of the pipeline (thesis §6.2.2).
#include "linesurf/render/splat_context.h"

#include <algorithm>
#include <cmath>

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
  requireRange("zThreshold", o.zThreshold, 0, 1e6);
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

FrameContext FrameContext::make(const Camera& camera, const RenderOptions& options, const BoundingSphere& sphere,
                                bool modelHasColors, const Image* texture) {
  FrameContext f;
  f.camera = &camera;
  f.options = &options;
  f.texture = texture;
  f.sphere = sphere;
  f.modelHasColors = modelHasColors;
  Vec3f l = options.light.direction.normalized();
  f.lightDirCamera = options.light.headlight ? l : Vec3f((camera.rotation() * l).normalized());
  f.fixedZThreshold = options.zThreshold * (sphere.radius > 0 ? sphere.radius : 1.0f);
  f.cutoffQ = options.cutoffRadius * options.cutoffRadius;
  f.frustum = camera.frustumPlanes();
  const Material& m = options.material;
  if (m.specular > 0 && m.shininess <= 128) {
    auto table = std::make_shared<std::vector<float>>(kSpecularTable + 2);
    for (int i = 0; i <= kSpecularTable + 1; ++i)
      (*table)[i] = std::pow(std::min(1.0f, float(i) / kSpecularTable), m.shininess);
    f.specularPow = std::move(table);
  }
  return f;
}

Vec3f FrameContext::shade(const Vec3f& albedo, const Vec3f& n, const Vec3f& p) const {
  const Material& m = options->material;
  const Vec3f& l = lightDirCamera;
  float ndl = std::max(0.0f, n.dot(l));
  Vec3f out = albedo * (m.ambient + m.diffuse * ndl);
  if (m.specular > 0 && ndl > 0) {
    float pn = p.norm();
    Vec3f v = pn > 0 ? Vec3f(-p / pn) : Vec3f(0, 0, 1);
    Vec3f h = (l + v);
    float hn = h.norm();
    if (hn > 0) {
      const float ndh = std::clamp(n.dot(h) / hn, 0.0f, 1.0f);
      float power;
      if (specularPow) {
        const float x = ndh * kSpecularTable;
        const int i = int(x);
        const float* t = specularPow->data();
        power = t[i] + (x - float(i)) * (t[i + 1] - t[i]);
      } else {
        power = std::pow(ndh, m.shininess);
      }
      out.array() += m.specular * power;
    }
  }
  return out.cwiseProduct(options->light.color);
}

}  // namespace linesurf
