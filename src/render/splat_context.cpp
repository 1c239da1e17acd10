// Per-frame constants and Phong lighting of the pipeline (thesis §6.2.2).
#include "splat_context.h"

#include <algorithm>
#include <cmath>


namespace linesurf {

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
  f.zRule = detail::ZThresholdRule::make(options, sphere.radius);
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
