#pragma once
/// The state of a segment splat that the common case does not need (thesis §5): the ScreenSpace
/// sub-segments beyond the first, the Reference nodes (segment_filter.h), the Approx
/// quadrilaterals (§5.2.3, segment_approx.h) and the Gouraud stations of a turning or textured
/// segment. Allocated only when a segment needs it, kept per record slot from frame to frame
/// (segment_splat.h: PreparedSegment::extra).
#include <memory>
#include <vector>

#include "linesurf/core/math.h"
#include "segment_rows.h"

namespace linesurf {

/// Largest number of ScreenSpace sub-segments per segment.
inline constexpr int kMaxSegmentPieces = 32;

/// One sub-segment of the ScreenSpace method (segment_rows.h: the SIMD rows evaluate them).
using SegmentPiece = detail::SegmentPiece;

/// One node of the Reference quadrature.
struct SegmentNode {
  float m00 = 1, m01 = 0, m11 = 1;  ///< M(t)^-1 in (a, b)
  float scale = 0;                  ///< dt / (h sqrt(det M(t)))
};

/// One weight-texture-mapped quadrilateral of the Approx method (§5.2.3.2).
struct SegmentQuad {
  Vec2f corner[4];  ///< plane coordinates (a, b); bilinear order 00, 10, 11, 01 (a cycle)
  Vec2f tex[4];     ///< weight-texture coordinates (x inward from the endpoint, y across)
  float scale[4];   ///< weight scaling factor at the corners (Figure 19)
  bool middle = false;   ///< T2 (middle portion) instead of T1 (endpoint portion)
  float tail = 1e30f;    ///< texture length of the segment: T1(x) - T1(x - tail) (short case)
  Vec2f lo = Vec2f::Zero(), hi = Vec2f::Zero();  ///< bounding box of the corners
};

namespace segment {
struct WeightTextures;  // §5.2.3.2 tables, segment_approx.cpp
}

/// What the common case does not need, allocated only when a segment needs it.
struct SegmentExtra {
  /// ScreenSpace with K > 1 sub-segments, evenly spaced (piece k covers [k, k+1] /
  /// pieceInvLength); a pixel at a only meets the pieces within pieceMaxReach (the largest reach).
  std::vector<SegmentPiece> pieces;
  float pieceInvLength = 0, pieceMaxReach = 0;
  /// Reference: nodes at spacing nodeStep starting at nodeStep / 2.
  std::vector<SegmentNode> nodes;
  float nodeStep = 0, nodeReach = 0;
  /// Approx: 10 quads (long case) or 8 (short).
  std::vector<SegmentQuad> quads;
  bool longCase = true;
  const segment::WeightTextures* textures = nullptr;
  /// Shading at stations evenly spaced over [0, length] (Gouraud, §6.2.2): the lit colour when
  /// untextured; textured, colour = albedo * diffuse + specular with the albedo from the
  /// texture (§5.2.4: uv interpolated between the endpoints).
  std::vector<Vec3f> diffuse, specular;
  /// untextured: the lit colour of station k, channel c at [c * stations + k], then
  /// detail::kMaxLanes floats of padding (the SIMD rows load whole vectors of a channel)
  std::vector<float> colour;
  int stations = 0;
  bool textured = false;
  Vec2f uv0 = Vec2f::Zero(), uv1 = Vec2f::Zero();

  /// Back to a default-constructed SegmentExtra's state, keeping the vectors' capacity (the
  /// renderer's record slots keep their SegmentExtra from frame to frame; see docs/decisions.md, "Segment records").
  /// Every member above must be reset here.
  void reset() {
    pieces.clear();
    pieceInvLength = pieceMaxReach = 0;
    nodes.clear();
    nodeStep = nodeReach = 0;
    quads.clear();
    longCase = true;
    textures = nullptr;
    diffuse.clear();
    specular.clear();
    colour.clear();
    stations = 0;
    textured = false;
    uv0 = uv1 = Vec2f::Zero();
  }
};

/// Resets a record slot's SegmentExtra (if it has one) for the next segment, keeping the
/// allocation: only a segment that needs it reads it (method, pieceCount, shade say which).
inline void resetExtra(std::unique_ptr<SegmentExtra>& extra) {
  if (extra) extra->reset();
}

}  // namespace linesurf
