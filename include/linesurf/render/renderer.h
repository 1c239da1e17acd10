#pragma once
/// The software splatting pipeline of thesis §6.2 for hybrid point + line-segment models:
/// per-primitive prepare (culling, transform, warping, clipping, lighting; in parallel), binning
/// into square screen tiles (deterministic: primitive index order within a tile, points before
/// segments), per-tile rasterisation into a modified-Z^3 buffer (tiles in parallel), and the
/// back-to-front resolve composited over the background. Images are identical for any thread
/// count.
#include <cstdint>
#include <memory>
#include <vector>
#include <optional>

#include "linesurf/core/image.h"
#include "linesurf/core/model.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/render_options.h"
#include "linesurf/render/render_stats.h"

namespace linesurf {

struct RenderResult {
  Image color;                 ///< RGBA, composited over options.background
  std::optional<Image> depth;  ///< R = G = B = linear depth of the nearest surface, A = 1 where covered
  std::optional<Image> alpha;  ///< R = G = B = A = coverage alpha before the background
  std::optional<Image> normal; ///< camera-space normal (n + 1) / 2 as RGB, A = 1 where covered
  RenderStats stats;
};

/// Renders a model: prepares what is per-model (bounding sphere, colour flags) once, then any
/// number of views.
class Renderer {
 public:
  /// Keeps a reference to `model`, which must outlive the Renderer. Throws BadParameter on
  /// invalid options (validate()).
  Renderer(const HybridModel& model, const RenderOptions& options = {});
  RenderResult render(const Camera& camera) const;
  /// The same with RenderOptions::facingCheck given for this view: the check costs about two
  /// prepare passes (more than a 512² frame of the model), so a series of views may check one.
  RenderResult render(const Camera& camera, bool facingCheck) const;
  const BoundingSphere& sphere() const { return sphere_; }
  const RenderOptions& options() const { return options_; }

  /// RenderOptions::facingCheck renders at most this many pixels along the longer side.
  static constexpr int kFacingCheckSide = 160;
  /// ... and takes a culled pixel this much of the bounding radius deeper than the two-sided one
  /// for a back face.
  static constexpr float kFacingDepthTolerance = 0.02f;

 private:
  RenderResult renderFrame(const Camera& camera, const RenderOptions& options) const;
  void measureFacing(const Camera& camera, RenderStats& stats) const;
  const HybridModel& model_;
  RenderOptions options_;
  BoundingSphere sphere_;
  /// Coverage alpha (RenderOptions::coverageGain): the primitives' coverage constants (points,
  /// then segments; src/render/coverage.h), their largest, and whether every primitive is opaque
  /// (the mode's condition)
  std::vector<float> coverage_;
  float coverageMax_ = 0;
  /// Tail coverage (RenderOptions::tailCoverage): the model's median coverage constant
  float tailCoverageC_ = 0;
  bool opaqueModel_ = true;
  struct Buffers;  // per-frame buffers reused by the next frame (renderer.cpp)
  std::shared_ptr<Buffers> buffers_;
};

/// The SIMD target the rasteriser's rows run on in this process, chosen at run time (Highway's
/// name: AVX3_ZEN4, AVX3, AVX2, SSE4, SSSE3, EMU128, ...). For benchmark tables.
const char* renderSimdTarget();

/// One-shot: Renderer(model, options).render(camera).
RenderResult renderImage(const HybridModel& model, const Camera& camera, const RenderOptions& options = {});

}  // namespace linesurf
