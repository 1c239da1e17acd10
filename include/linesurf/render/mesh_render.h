#pragma once
/// Triangle meshes as a render primitive: the ground truth a splat image of the same surface is
/// compared with (beyond the thesis; docs/decisions.md, "Mesh ground truth and the
/// silhouette band"). Anti-aliased by supersampling: every pixel holds
/// S x S samples on a regular grid, each z-buffered (nearest triangle wins, ties to the lower
/// face index); a pixel's colour is the box-filtered average of its samples, each shaded by the
/// same Phong model (RenderOptions::material, light) as the splats, per pixel and per triangle at
/// the centroid of the triangle's samples in that pixel, with normals interpolated from the
/// vertex normals (area-weighted when the mesh has none, core/mesh_normals.h). Same Camera,
/// background, colour/alpha conventions and output buffers as Renderer (renderer.h), so the two
/// images are directly comparable. Tiles are rendered in parallel, each from its own triangle list
/// in face order: identical images for any thread count.
#include <cstdint>
#include <optional>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/model.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/render_options.h"

namespace linesurf {

struct MeshRenderOptions {
  /// Samples per pixel side (S x S samples per pixel), [1, 16]. Default 4 (16 samples: edges
  /// within 1/16 of a grey step of the exact coverage on average).
  int supersampling = 4;
  /// true: normals interpolated from the vertex normals (smooth shading); false: face normals.
  bool smoothShading = true;
};

struct MeshRenderStats {
  uint64_t trianglesDrawn = 0, trianglesClipped = 0, trianglesCulled = 0, trianglesOutside = 0,
           trianglesDegenerate = 0;
  uint64_t samplesCovered = 0;  ///< samples whose nearest surface is a triangle
  double prepareSeconds = 0, rasterSeconds = 0, totalSeconds = 0;
  /// Adds every counter and time of `o` (several views of one mesh).
  MeshRenderStats& operator+=(const MeshRenderStats& o);
};

struct MeshRenderResult {
  Image color;                 ///< RGBA, composited over options.background (as RenderResult)
  std::optional<Image> depth;  ///< R = G = B = depth of the nearest sample, A = 1 where covered
  std::optional<Image> alpha;  ///< coverage alpha before the background
  std::optional<Image> normal; ///< camera-space normal (n + 1) / 2, A = 1 where covered
  MeshRenderStats stats;
};

/// Bounding sphere of the mesh's vertices (centre of the bounding box, radius to the farthest
/// finite vertex), as boundingSphere(HybridModel) does for points of radius 0.
BoundingSphere boundingSphere(const TriangleMesh& mesh);

/// Renders a mesh from any number of views; vertex normals and the sphere are computed once.
class MeshRenderer {
 public:
  /// Keeps a reference to `mesh`, which must outlive the renderer. Throws linesurf::Error:
  /// BadParameter for invalid options, BadInput for a face index out of range.
  MeshRenderer(const TriangleMesh& mesh, const RenderOptions& options = {}, const MeshRenderOptions& meshOptions = {});
  MeshRenderResult render(const Camera& camera) const;
  const BoundingSphere& sphere() const { return sphere_; }

 private:
  const TriangleMesh& mesh_;
  RenderOptions options_;
  MeshRenderOptions meshOptions_;
  BoundingSphere sphere_;
  std::vector<Vec3f> normals_;  ///< unit vertex normals (zero where undefined)
};

/// One-shot: MeshRenderer(mesh, options, meshOptions).render(camera).
MeshRenderResult renderMesh(const TriangleMesh& mesh, const Camera& camera, const RenderOptions& options = {},
                            const MeshRenderOptions& meshOptions = {});

}  // namespace linesurf
