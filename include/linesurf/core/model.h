#pragma once
/// Core model types (thesis §1.2, §3): the point primitive, the line-segment primitive, the
/// hybrid model holding both, and the triangle mesh that §3.3 cuts into segments.
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"

namespace linesurf {

/// A point primitive: a small elliptical-disc surface element (surfel, thesis §2.1).
struct Point {
  Vec3f position = Vec3f::Zero();  ///< object space
  Vec3f normal = Vec3f::Zero();    ///< unit length, or zero when unknown
  Color color = Color(1, 1, 1, 1); ///< linear RGBA in [0,1]
  float radius = 0;                ///< object-space radius of the surface element (0 = unknown)
};

/// A line-segment primitive (thesis §1.2): a strip of surface of half-width `radius` around
/// the segment p0-p1, with one normal perpendicular to the segment.
struct Segment {
  Vec3f p0 = Vec3f::Zero(), p1 = Vec3f::Zero();  ///< endpoints, object space
  Vec3f normal = Vec3f::Zero();                  ///< unit, perpendicular to p1 - p0
  /// Optional shading normals at p0 and p1 (smooth line models, beyond the thesis): unit, on
  /// the side of `normal`; the surface normal there, so they may lean along the segment (issue
  /// 14: extractors that make them perpendicular stay valid). The renderer shades with
  /// normalize(normal0 + u (normal1 - normal0)). Zero when the segment carries only `normal`
  /// (the thesis's one-normal segment); see Attributes.
  Vec3f normal0 = Vec3f::Zero(), normal1 = Vec3f::Zero();
  Color color = Color(1, 1, 1, 1);               ///< linear RGBA in [0,1]
  float radius = 0;                              ///< half-width of the strip, object space
  Vec2f uv0 = Vec2f::Zero(), uv1 = Vec2f::Zero(); ///< texture coordinates at the endpoints (§5.2.4)
  float length() const { return (p1 - p0).norm(); }
};

/// Which optional attributes a model carries. A file without normals gives hasNormals = false
/// and zero normals; later stages (geometry, §6.1) fill them in.
struct Attributes {
  bool normals = false;
  bool colors = false;
  bool radii = false;
  bool texcoords = false;  ///< segments carry uv0/uv1
  bool endpointNormals = false;  ///< segments carry normal0/normal1 (PLY nx0..nz0, nx1..nz1)
  /// points carry HybridModel::pointShadingNormals (PLY snx sny snz)
  bool shadingNormals = false;
};

/// A hybrid point + line-segment model (thesis §3). A point cloud is a HybridModel without
/// segments.
struct HybridModel {
  std::vector<Point> points;
  std::vector<Segment> segments;
  Attributes attributes;
  /// Texture image sampled by segment uv (§5.2.4); null when untextured.
  std::shared_ptr<const Image> texture;
  /// Optional per-point shading normals (beyond the thesis), used when
  /// attributes.shadingNormals: unit, one per point, in point order. A point's `normal` stays
  /// its splat plane and its back-face test; the shading normal only lights it (flat and
  /// Gouraud shading, the deferred normal buffer). Contour point models carry the interpolated
  /// vertex normal here while their planes keep near their triangle (docs/decisions.md,
  /// "Smooth contour models"). Kept beside `points`, not in Point (the renderer's hot data).
  std::vector<Vec3f> pointShadingNormals;
  /// Extra per-point scalar properties (e.g. curvature "k_min"), each of points.size().
  /// One is read by the renderer: kPointMassProperty ("mass", see pointMasses()).
  std::map<std::string, std::vector<float>> pointProperties;
  /// Extra per-segment scalar properties, each of segments.size(): the extractions give a
  /// segment its points' properties (the mean, the mode for a class: docs/decisions.md "Point
  /// attributes on kept points and segments"); PLY `segment` element properties of those names.
  std::map<std::string, std::vector<float>> segmentProperties;
  /// Optional per-segment list of the input point indices it replaced (--provenance).
  std::vector<std::vector<uint32_t>> provenance;
  /// Free-form header comments kept through read/write (e.g. "source: ...").
  std::vector<std::string> comments;

  bool empty() const { return points.empty() && segments.empty(); }
  Bounds3f bounds() const;
};

/// The point property that scales a point splat's kernel (beyond the thesis; docs/decisions.md
/// "Point masses"): finite, > 0, in units of the thesis's splat (1). A splat of mass m weighs as m
/// coincident ones, so a model whose points stand for unequal parts of the surface reconstructs it
/// without leaning towards its denser places. Contour point models carry the contour length each
/// point stands for over its radius, which is what a segment weighs per length (a segment of
/// length l weighs as l / radius points; render/segment_splat.h). Absent: every point weighs 1
/// (the thesis).
inline constexpr const char* kPointMassProperty = "mass";

/// The largest point mass a model may carry (a larger one is garbage or a unit error).
inline constexpr float kMaxPointMass = 1e6f;

/// Whether `m` is a valid point mass: in (0, kMaxPointMass] (so finite).
inline bool validPointMass(float m) { return m > 0 && m <= kMaxPointMass; }

/// The model's point masses (pointProperties[kPointMassProperty]) when it has one per point,
/// else null.
inline const std::vector<float>* pointMasses(const HybridModel& model) {
  auto it = model.pointProperties.find(kPointMassProperty);
  return it != model.pointProperties.end() && it->second.size() == model.points.size() && !model.points.empty()
             ? &it->second
             : nullptr;
}

/// A triangle mesh (input of §3.3).
struct TriangleMesh {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;   ///< per vertex; empty or positions.size()
  std::vector<Color> colors;    ///< per vertex; empty or positions.size()
  std::vector<std::array<uint32_t, 3>> faces;
  /// Per-corner texture coordinates; empty or faces.size().
  std::vector<std::array<Vec2f, 3>> cornerUVs;
  std::shared_ptr<const Image> texture;  ///< texture image; null when none
  std::vector<std::string> comments;

  Bounds3f bounds() const;
};

}  // namespace linesurf
