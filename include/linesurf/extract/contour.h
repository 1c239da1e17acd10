#pragma once
/// Contour-plane extraction of line-segment models from triangle meshes, thesis §3.3.
///
/// The mesh is cut by two perpendicular families of parallel planes, P= and P‖, each the lattice
/// n·x = offset + i·d (i integer). Every triangle is cut by one family only, at the spacing
/// d / 2^m with m = ⌈log2(1 / sin θ)⌉ (θ: angle between the triangle and the family's planes), so
/// that neighbouring segments on the triangle are at most d apart; the finer spacings are
/// sub-lattices of the same family, so a plane of spacing d cuts every triangle that uses that
/// family, and the pieces meet exactly on shared edges. Segments can be turned into points
/// (hybrid model) or all of them into ⌈l/d⌉+1 points each (the pure point model of Table 5).
/// The rules we chose where the thesis leaves room (family choice, default d, radius, plane
/// through a vertex) are in docs/decisions.md, "Contour-plane extraction (§3.3)".
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"

namespace linesurf {

/// The two perpendicular plane families. Family 0 is P= (tried first), family 1 is P‖.
/// Plane i of family f is {x : normal[f]·x = offset[f] + i·d}.
struct ContourPlanes {
  Vec3d normal[2] = {Vec3d(0, 0, 1), Vec3d(1, 0, 0)};  ///< unit, mutually perpendicular
  double offset[2] = {0, 0};                           ///< object units
};

/// Plane families for a seed: a uniformly random rotation, redrawn while a plane normal is within
/// ~25° of a coordinate axis (the thesis wants orientations "not aligned with the bases of the
/// coordinate system"), and offsets uniform in [0, spacing). Deterministic and platform-independent.
ContourPlanes randomContourPlanes(uint64_t seed, double spacing);

struct ContourOptions {
  /// d: the largest distance between neighbouring segments on a triangle, object units.
  /// 0 (default) = spacingScale × the mesh's mean edge length. Must stay below twice the cutoff
  /// radius of the rendering kernel (§3.3); the output radius below is derived from it.
  float spacing = 0;
  float spacingScale = 1.0f;  ///< used when spacing == 0; > 0
  /// Cap on the default d (beyond the thesis; docs/decisions.md "Spacing and radius"): when spacing
  /// == 0, d = spacingScale × min(mean edge length, bounding-box diagonal / diagonalDivisions). The
  /// mean edge alone makes a coarse mesh's model coarser than the thesis's own (Al, 7k faces: mean
  /// edge = diagonal / 52, 27,625 contour points; the thesis's Al has 163,205; at the cap 163,909),
  /// and its splats blur every feature the size of an edge. 0 = no cap. See contourSpacing.
  float diagonalDivisions = 200;
  uint64_t seed = 1;          ///< orientation and offsets of the planes
  std::optional<ContourPlanes> planes;  ///< explicit plane families (overrides seed)
  /// Family choice per triangle: P= is used unless its sin θ is below this value and P‖ cuts at a
  /// larger angle. 1 (default): always the family with the larger sin θ (fewest segments, spacing
  /// d or d/2 only); 0: P= wherever it cuts at all (one family: closed contours).
  float familySwitchSine = 1.0f;
  /// Radius of every output segment and point = radiusScale × d. The thesis's constraint
  /// d < 2R (R: kernel cutoff radius) needs radiusScale > 0.5 for a hole-free rendering. 0.55
  /// (was 0.75; docs/decisions.md "Spacing and radius"): strips reach beyond the surface by their
  /// radius at silhouettes and creases; 0.55 d cut the pixels off the mesh image by > 64 levels on
  /// Al from 14.4% to 11.1%.
  float radiusScale = 0.55f;
  /// Segment normal from the vertex normals interpolated at the midpoint (made perpendicular to
  /// the segment) instead of the triangle's normal (thesis). Ignored when the mesh has none.
  bool vertexNormals = false;
  /// Smooth line models (beyond the thesis): every segment also carries the vertex normals
  /// interpolated at its endpoints (Segment::normal0/normal1, made perpendicular to it);
  /// area-weighted vertex normals are computed when the mesh has none. The segment's own
  /// `normal` (its strip's plane, culling) and every point's normal are then the vertex normals
  /// interpolated there (made perpendicular to the segment), leaning at most 10 degrees from the
  /// triangle's normal (further, back-face culling opens holes at creases), so that the line
  /// model and the point model cut from it shade and cover alike (Table 5's mean
  /// absolute difference on Al 2.95 -> 1.97; docs/decisions.md "Smooth contour models"). false: the
  /// thesis's one-normal model (the triangle's normal, or as vertexNormals says).
  bool endpointNormals = true;
  /// Shading normals for smooth models (beyond the thesis; only with endpointNormals):
  /// every point carries the interpolated vertex normal, full and unit, as its shading normal
  /// (HybridModel::pointShadingNormals; its `normal` stays the plane above), and the segments'
  /// endpoint normals keep their component along the segment (the interpolated vertex normals
  /// themselves), so that lines and points both shade with the mesh's smooth normal. false: the
  /// endpoint normals are made perpendicular to the segment and points carry no shading normal
  /// (the first smooth model). Measured in docs/decisions.md, "Smooth contour models".
  bool shadingNormals = true;
  /// Point masses (beyond the thesis): every point made from a segment carries the
  /// length of that segment it stands for over its radius as its mass (pointMasses; half a spacing
  /// at either end, so the two points where neighbouring faces' segments meet add up to one), the
  /// weight a segment of that length has. Without them the points weigh 1 each and their unequal
  /// spacing along the contours (the faces' segments are cut at every mesh edge) shows as streaks
  /// along the contours; measured in docs/decisions.md, "Point masses". Only when
  /// points are made (allPoints, pointsBelow).
  bool pointMasses = true;
  /// Polyline merging (beyond the thesis): consecutive segments of one contour polyline
  /// (one plane, chained through shared mesh edges; never across a break, a family or a plane)
  /// become one segment while every original vertex in between stays within
  /// mergeNormalDeviation × d of it along the surface normal there and within
  /// mergeTangentDeviation × d across it in the surface, and the normals agree within mergeAngle
  /// degrees: every piece's strip plane with the merged strip's plane and, for smooth models, the
  /// merged endpoint normals interpolated along it (as the renderer does) with the vertex normals
  /// at the interior vertices. Colours (and uvs on textured meshes) must stay continuous too. At
  /// most mergeMaxPieces segments become one. mergeNormalDeviation = 0 or mergeMaxPieces = 1: no
  /// merging (one segment per face and plane crossed, the thesis's model). Ignored with allPoints
  /// (the point model of Table 5 is cut from the unmerged segments). Every merge moved Table 5's
  /// line-vs-point difference up a little, in proportion to how much was merged (whichever limit
  /// binds), while the line model's difference from the mesh itself stays unchanged (SSIM, PSNR
  /// and the > 64 share within 0.0002 / 0.01 dB / 0.01 points). 2 degrees (the
  /// default): 3-37% fewer segments than 0.5, Table 5 +0.009 to +0.046 on the seven shared meshes
  /// (docs/decisions.md, "Polyline merging", with the 0.5, 1 and 5 degrees measured). The tangent
  /// deviation 0.05 d = radiusScale - 0.5: neighbouring strips (d apart, half-width 0.55 d) still
  /// overlap.
  float mergeNormalDeviation = 0.01f;
  float mergeTangentDeviation = 0.05f;
  float mergeAngle = 2.0f;
  /// Smooth models (endpointNormals): largest angle between a merged segment's strip plane and
  /// the planes of the pieces it replaces, degrees [0, 90) (beyond the thesis). The
  /// strip plane only places the strip (its edges move by half-width × sin of the tilt: 0.019 d
  /// at 2 degrees) and culls it; the shading comes from the endpoint normals, which mergeAngle
  /// still bounds at every interior vertex. 4 (was mergeAngle): 4-18% fewer segments on
  /// bunny, horse, gargoyle, dragon, line frames 8-13 points faster against their point models,
  /// the line-vs-mesh SSIM within 0.0001, Table 5 +0.003 to +0.022 (docs/decisions.md,
  /// "Polyline merging"). Flat models use mergeAngle for the strip (it is their shading normal).
  float mergeStripAngle = 4.0f;
  int mergeMaxPieces = 32;
  /// Segments shorter than this (object units) become ⌈l/d⌉+1 points: hybrid model. 0 = none.
  float pointsBelow = 0;
  /// Every segment becomes ⌈l/d⌉+1 points at regular intervals: pure point model (Table 5).
  bool allPoints = false;
  /// Fill ContourStats::segmentFaces / pointFaces (source triangle of each primitive).
  bool recordFaces = false;
  /// Refuse to produce more primitives than this (protects against a tiny --spacing).
  size_t maxPrimitives = size_t(1) << 31;
  ProgressFn progress;  ///< optional, stage "contour planes"
};

struct ContourStats {
  size_t triangles = 0;            ///< faces in the mesh
  size_t degenerateTriangles = 0;  ///< zero-area or non-finite faces, skipped
  size_t cutByFamily[2] = {0, 0};  ///< non-degenerate faces cut (or not) with P= / P‖
  size_t halvedSpacing = 0;        ///< faces that needed a finer level (m >= 1)
  size_t uncutTriangles = 0;       ///< faces that no plane of their lattice crosses
  size_t vertexTouches = 0;        ///< planes touching a face only at a vertex (no segment)
  size_t segments = 0;             ///< segments in the output (after merging)
  size_t segmentsBeforeMerge = 0;  ///< one per face and plane crossed (= segments without merging)
  size_t polylines = 0;            ///< contour polylines found when merging (0 without merging)
  size_t points = 0;               ///< points in the output
  size_t convertedSegments = 0;    ///< segments turned into points
  double spacing = 0;              ///< d used
  double meanEdgeLength = 0;       ///< over non-degenerate faces (each face's three edges)
  double diagonal = 0;             ///< of the mesh's bounding box (all vertices)
  bool spacingFromDiagonal = false;  ///< d came from diagonal / diagonalDivisions (the cap)
  double radius = 0;               ///< primitive radius written
  double seconds = 0;              ///< wall time of extractContour
  ContourPlanes planes;            ///< the plane families used
  std::vector<uint32_t> segmentFaces;  ///< with recordFaces: source face of each segment
  std::vector<uint32_t> pointFaces;    ///< with recordFaces: source face of each point
};

/// Throws OptionError (core/options.h) naming the first bad field; NaN is always rejected.
void validate(const ContourOptions& options);

/// The plane spacing d that extractContour uses: options.spacing when > 0, else spacingScale ×
/// min(meanEdgeLength, diagonal / diagonalDivisions) (no cap when diagonalDivisions is 0 or the
/// diagonal is not positive). `capped` (optional) says whether the diagonal gave it.
double contourSpacing(const ContourOptions& options, double meanEdgeLength, double diagonal, bool* capped = nullptr);

/// Cuts `mesh` into a line-segment (or hybrid, or point) model, thesis §3.3.
/// Segments carry the triangle's unit normal (or interpolated vertex normals), a colour (texture
/// sampled at the midpoint's uv when the mesh has a texture and per-corner uvs, else interpolated
/// vertex colours, else white) and, with per-corner uvs, the barycentrically interpolated uvs of
/// their endpoints; the model shares the mesh's texture. Output order is deterministic (by face,
/// then plane) for any thread count.
/// Throws linesurf::Error: BadParameter for a negative/non-finite spacing, conflicting point
/// options, radiusScale <= 0 or an output above maxPrimitives; BadInput for a face index out of
/// range. Degenerate faces are counted in stats, never an error.
HybridModel extractContour(const TriangleMesh& mesh, const ContourOptions& options = {},
                           ContourStats* stats = nullptr);

}  // namespace linesurf
