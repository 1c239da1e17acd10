// The prepare stage's SIMD batches against its exact path (src/render/segment_setup.h,
// segment_splat.h): for many random segments (random orientations, lengths from 1e-4 to 3,
// radii from 3e-4 to 0.3, distances from 1.2 to 300, near-grazing strips, segments through the
// near plane, smooth normals turning by less and more than 0.1 rad, one- and two-sided, Gouraud
// and per-pixel lighting), prepareSegments gives every segment the status of prepareSegment and
// the same PreparedSegment constants to the tolerances stated in `agree` (float rounding), except
// that a segment at the viewport's edge may differ by one pixel of bounds (and so between Drawn,
// Clipped and Outside). The lanes the SIMD code cannot decide go to prepareSegment itself: the
// test checks that they are a minority, and not none (the awkward cases above are among them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <hwy/targets.h>

#include "linesurf/render/camera.h"
#include "render/segment_setup.h"
#include "render/segment_splat.h"

namespace linesurf {
namespace {

struct Case {
  std::vector<Segment> segs;
};

// Random segments around the origin; every 8th strip is nearly edge-on to the eye unless `turning`;
// smooth: every 5th one's normal turns by 0.3 rad along it, the others' by less than 0.1 rad, or with
// `turning` every one's by 0.1 .. 1.3 rad (several lighting stations) and lengths 1e-3 .. 0.1 (as
// contour models' segments: one sub-segment).
std::vector<Segment> randomSegments(int n, const Vec3f& eye, bool smooth, uint32_t seed, bool turning = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1), u01(0, 1);
  auto dir = [&] {
    Vec3f v;
    do v = Vec3f(u(rng), u(rng), u(rng));
    while (!(v.squaredNorm() > 1e-4f && v.squaredNorm() <= 1));
    return Vec3f(v.normalized());
  };
  std::vector<Segment> out;
  for (int i = 0; i < n; ++i) {
    Segment s;
    const Vec3f c = dir() * std::pow(u01(rng), 0.5f) * 1.5f;
    const Vec3f e = dir();
    const float len = turning ? std::pow(10.0f, -3 + 2 * u01(rng)) : std::pow(10.0f, -4 + 4.5f * u01(rng));
    s.p0 = c - 0.5f * len * e;
    s.p1 = c + 0.5f * len * e;
    s.radius = std::pow(10.0f, -3.5f + 3 * u01(rng));
    Vec3f n = dir();
    if (i % 8 == 0 && !turning) n = (eye - c).normalized().cross(e) + 0.01f * u(rng) * dir();  // near grazing
    n -= n.dot(e) * e;
    s.normal = n.normalized();
    if (smooth) {
      const float turn = turning ? 0.1f + 1.2f * u01(rng) : i % 5 == 0 ? 0.3f : 0.08f * u01(rng);
      const Vec3f side = e.cross(s.normal);
      s.normal0 = (s.normal * std::cos(turn / 2) - side * std::sin(turn / 2)).normalized();
      s.normal1 = (s.normal * std::cos(turn / 2) + side * std::sin(turn / 2)).normalized();
    }
    s.color = Color(u01(rng), u01(rng), u01(rng), 1);
    out.push_back(s);
  }
  return out;
}

bool visible(PrimitiveStatus s) { return s == PrimitiveStatus::Drawn || s == PrimitiveStatus::Clipped; }

// The constants of a (visible) prepared segment agree with the exact stages' to float rounding:
// relative 1e-3 for the footprint and the piece (the float covariance is good to 1e-4), plane
// coordinates at the segment's middle to 1e-3 of the footprint plus 1e-5 of the terms summed
// (float rounding, magnified as the ray grazes the plane), colours to 2e-3.
std::string agree(const PreparedSegment& f, const PreparedSegment& x, const Vec2f& centre) {
  const detail::SegmentRaster &a = f.raster, &b = x.raster;
  using detail::Affine2;
  std::string err;
  auto rel = [&](const char* what, float p, float q, float scale, float tol) {
    if (!(std::abs(p - q) <= tol * scale)) err += std::string(what) + " " + std::to_string(p) + " vs " + std::to_string(q) + "; ";
  };
  if (std::abs(f.bounds.x0 - x.bounds.x0) > 1 || std::abs(f.bounds.x1 - x.bounds.x1) > 1 ||
      std::abs(f.bounds.y0 - x.bounds.y0) > 1 || std::abs(f.bounds.y1 - x.bounds.y1) > 1)
    err += "bounds; ";
  if (f.method != x.method || f.useSpans != x.useSpans || f.smooth != x.smooth || f.shade != x.shade ||
      f.pieceCount() != x.pieceCount() || a.clipDepth != b.clipDepth || f.index != x.index)
    err += "kind; ";
  const float ext = b.aMax - b.aMin + b.bMax;
  rel("length", a.length, b.length, b.length, 1e-5f);
  rel("aMin", a.aMin, b.aMin, ext, 1e-3f);
  rel("aMax", a.aMax, b.aMax, ext, 1e-3f);
  rel("bMax", a.bMax, b.bMax, b.bMax, 1e-3f);
  // the kernel constants a piece and the record's first piece share
  auto kernel = [&](const auto& p, const auto& q) {
    rel("skew", p.skew, q.skew, std::max(1.0f, std::abs(q.skew)), 1e-3f);
    rel("across", p.across, q.across, q.across, 1e-3f);
    rel("invM00", p.invM00, q.invM00, q.invM00, 1e-3f);
    rel("k", p.k, q.k, q.k, 1e-3f);
    rel("erfScale", p.erfScale, q.erfScale, q.erfScale, 1e-3f);
    rel("scale0", p.scale0, q.scale0, q.scale0, 1e-3f);
  };
  kernel(a, b);
  rel("slope*L", a.slope * a.length, b.slope * b.length, b.scale0, 2e-3f);
  if (f.pieceCount() > 1 && x.pieceCount() == f.pieceCount()) {  // the sub-segments (in extra)
    rel("pieceInvLength", a.pieceInvLength, b.pieceInvLength, b.pieceInvLength, 1e-4f);
    rel("pieceMaxReach", a.pieceMaxReach, b.pieceMaxReach, ext, 1e-3f);
    if (a.pieces != f.extra->pieces.data() || b.pieces != x.extra->pieces.data() ||
        f.extra->pieces.size() != size_t(f.pieceCount()) || x.extra->pieces.size() != size_t(x.pieceCount()))
      err += "pieces; ";
    else
      for (int k = 0; k < f.pieceCount(); ++k) {
        const SegmentPiece &p = a.pieces[k], &q = b.pieces[k];
        rel("piece a0", p.a0, q.a0, ext, 1e-4f);
        rel("piece a1", p.a1, q.a1, ext, 1e-4f);
        rel("piece reach", p.reach, q.reach, ext, 1e-3f);
        const float m = std::max({std::abs(q.m00), std::abs(q.m11), std::abs(q.m01)});
        rel("piece m00", p.m00, q.m00, m, 1e-3f);
        rel("piece m01", p.m01, q.m01, m, 1e-3f);
        rel("piece m11", p.m11, q.m11, m, 1e-3f);
        kernel(p, q);
        rel("piece scale1", p.scale1, q.scale1, q.scale1, 1e-3f);
        rel("piece slope*len", p.slope * (p.a1 - p.a0), q.slope * (q.a1 - q.a0), q.scale0, 2e-3f);
      }
  }
  rel("zThreshold0", a.zThreshold0, b.zThreshold0, b.zThreshold0, 1e-3f);
  rel("zThreshold1", a.zThreshold1, b.zThreshold1, b.zThreshold1, 1e-3f);
  // the ray through `centre` (the segment's middle) meets the plane at the same depth and (a, b),
  // to the rounding of the terms each path sums, magnified where the ray grazes the plane
  const float px = centre.x(), py = centre.y();
  const float na = a.N.at(px, py), nb = b.N.at(px, py);
  const float graze = (std::abs(b.N.dx * px) + std::abs(b.N.dy * py) + std::abs(b.N.c)) / std::abs(nb);
  const float ta = a.depthNum / na, tb = b.depthNum / nb;
  rel("depth", ta, tb, std::abs(tb), 1e-5f * graze + 1e-4f);
  auto terms = [&](const Affine2& A, float c) {
    return (std::abs(A.dx * px) + std::abs(A.dy * py) + std::abs(A.c)) / std::abs(nb) * graze + std::abs(c);
  };
  rel("a", a.A.at(px, py) / na - a.a0, b.A.at(px, py) / nb - b.a0, 1e-3f * ext + 1e-5f * terms(b.A, b.a0), 1);
  rel("b", a.B.at(px, py) / na - a.b0, b.B.at(px, py) / nb - b.b0, 1e-3f * ext + 1e-5f * terms(b.B, b.b0), 1);
  for (int k = 0; k < 4 && x.useSpans; ++k)
    for (int c = 0; c < 2; ++c)
      rel("quad", f.screenQuad[k][c], x.screenQuad[k][c], 1e-2f + 1e-5f * std::abs(x.screenQuad[k][c]), 1);
  for (int c = 0; c < Z3Tile::kAttrs; ++c) rel("attr", f.attr[c], x.attr[c], 1, 2e-3f);
  for (int c = 0; c < 3; ++c) rel("dc", f.dc[c], x.dc[c], 1, 2e-3f);
  if (x.smooth)
    for (int c = 0; c < 3; ++c) rel("n0", f.n0[c], x.n0[c], 1, 1e-4f), rel("dn", f.dn[c], x.dn[c], 1, 1e-4f);
  if (x.shade == SegmentShade::Stations && f.shade == SegmentShade::Stations) {  // the lighting stations
    // in the record (stationCount >= 0: none, or kInlineStations) or in extra, the same in both
    auto stations = [](const PreparedSegment& s, int& count, const float*& colour) {
      if (s.stationCount >= 0) return count = s.stationCount, colour = s.stationColour, true;
      if (!s.extra || s.extra->textured || s.extra->colour.size() != 3 * size_t(s.extra->stations) + detail::kMaxLanes) return false;  // padded
      return count = s.extra->stations, colour = s.extra->colour.data(), true;
    };
    int nf = -2, nx = -2;
    const float *cf = nullptr, *cx = nullptr;
    if (!stations(f, nf, cf) || !stations(x, nx, cx) || nf != nx || (f.stationCount >= 0) != (x.stationCount >= 0) ||
        (x.stationCount >= 0) != (nx == 0 || nx == kInlineStations))
      err += "stations; ";
    else
      for (int k = 0; k < 3 * nx; ++k) rel("station", cf[k], cx[k], 1, 2e-3f);
  }
  return err;
}

struct Tally {
  size_t segments = 0, scalar = 0;  ///< all, and those the SIMD code left to prepareSegment
  int compared = 0, edge = 0, visible = 0;
  int stations = 0;  ///< visible segments the exact path shades with several stations (shade Stations)
  int pieces = 0;    ///< compared segments with several sub-segments
};

// One frame: every segment's status and constants from the batches against the exact path's.
void check(const std::vector<Segment>& segs, const Camera& cam, const RenderOptions& o, bool endpointNormals,
           Tally& tally) {
  FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1.5f});
  frame.endpointNormals = endpointNormals;
  const size_t n = segs.size();
  std::vector<PreparedSegment> batched(n), exact(n);
  std::vector<PrimitiveStatus> sb(n), sx(n);
  // odd ranges, as the renderer's threads split them
  for (size_t i = 0; i < n; i += 97)
    tally.scalar += prepareSegments(segs.data(), uint32_t(i), std::min<size_t>(97, n - i), frame,
                                    segmentSetupFrame(frame), batched.data() + i, sb.data() + i);
  tally.segments += n;
  for (size_t i = 0; i < n; ++i) sx[i] = prepareSegment(segs[i], uint32_t(i), frame, exact[i]);
  const PixelRect view{0, 0, cam.width(), cam.height()};
  for (size_t i = 0; i < n; ++i) {
    if (sb[i] != sx[i]) {
      // only at the viewport's edge, within a pixel of the exact bounds
      const PixelRect& eb = visible(sx[i]) ? exact[i].bounds : batched[i].bounds;
      const bool edge = (visible(sb[i]) || sb[i] == PrimitiveStatus::Outside) &&
                        (visible(sx[i]) || sx[i] == PrimitiveStatus::Outside) &&
                        (std::abs(eb.x0 - view.x0) <= 1 || std::abs(eb.y0 - view.y0) <= 1 ||
                         std::abs(eb.x1 - view.x1) <= 1 || std::abs(eb.y1 - view.y1) <= 1 || eb.empty());
      EXPECT_TRUE(edge) << "segment " << i << " status " << int(sb[i]) << " vs exact " << int(sx[i]);
      ++tally.edge;
    } else if (visible(sb[i])) {
      const Vec3f mid = cam.toCamera(0.5f * (segs[i].p0 + segs[i].p1));
      const std::string err = agree(batched[i], exact[i], cam.project(mid).head<2>());
      EXPECT_TRUE(err.empty()) << "segment " << i << ": " << err;
      ++tally.compared;
      tally.pieces += exact[i].pieceCount() > 1;
    }
    tally.visible += visible(sx[i]);
    tally.stations += visible(sx[i]) && exact[i].shade == SegmentShade::Stations;
  }
}

TEST(SegmentPrepare, BatchesAgreeWithTheExactPath) {
  Tally tally;
  int frames = 0;
  for (float dist : {1.2f, 3.0f, 20.0f, 300.0f}) {
    const Vec3f eye = Vec3f(0.3f, 0.2f, 1).normalized() * dist;
    for (int variant = 0; variant < 4; ++variant) {
      const bool smooth = variant & 1;
      RenderOptions o;
      o.backfaceCulling = variant != 2;
      o.perPixelLighting = variant == 3;
      const float fov = dist > 50 ? 2.0f : 40.0f;
      const Camera cam = Camera::lookAt(eye, Vec3f::Zero(), Vec3f(0, 1, 0), fov, 320, 240, dist > 2 ? 0.05f : 0.5f, 1000);
      check(randomSegments(3000, eye, smooth, uint32_t(11 + variant + 7 * frames)), cam, o, smooth, tally);
      ++frames;
    }
  }
  // most segments are compared, few sit at the viewport's edge; the SIMD code decides most of
  // them (the rest: near grazing, turning normals, near-plane, long and near ones)
  EXPECT_GT(tally.compared, tally.visible * 99 / 100);
  EXPECT_LT(tally.edge, tally.compared / 200);
  EXPECT_LT(tally.scalar, tally.segments / 2);
  EXPECT_GT(tally.scalar, tally.segments / 100);
  EXPECT_GT(tally.pieces, 100);  // segments with several sub-segments compared
  std::printf("%zu segments, %zu to the exact path, %d visible, %d compared (%d with sub-segments), %d at the edge\n",
              tally.segments, tally.scalar, tally.visible, tally.compared, tally.pieces, tally.edge);
}

// Smooth segments whose shading normals turn by 0.1 .. 1.3 rad along them (contour line models
// keep their normals' along-segment part, so most of Al's turn by more than 0.1 rad) stay in the
// SIMD batches, with the exact path's lighting stations (Gouraud; none when lighting is deferred),
// shade and normals: the same segments with normals that do not turn go to the exact path (for
// their other reasons: near grazing, clamped covariance) as often, up to 1% of them (the lanes
// whose station count or turn test the float turn cannot decide), where every visible turning one
// did before (docs/decisions.md "Segment prepare").
TEST(SegmentPrepare, TurningSegmentsStayInTheBatches) {
  for (bool deferred : {false, true}) {
    Tally tally;
    size_t flatScalar = 0;
    for (float dist : {3.0f, 20.0f}) {
      const Vec3f eye = Vec3f(0.3f, 0.2f, 1).normalized() * dist;
      RenderOptions o;
      o.perPixelLighting = deferred;
      o.material.specular = 0.5f;  // a highlight the stations must keep
      const Camera cam = Camera::lookAt(eye, Vec3f::Zero(), Vec3f(0, 1, 0), 40, 320, 240, 0.05f, 1000);
      const std::vector<Segment> segs = randomSegments(3000, eye, true, uint32_t(5 + int(dist) + deferred), true);
      check(segs, cam, o, true, tally);
      std::vector<Segment> flat = segs;
      for (Segment& s : flat) s.normal0 = s.normal1 = s.normal;
      FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1.5f});
      frame.endpointNormals = true;
      std::vector<PreparedSegment> out(flat.size());
      std::vector<PrimitiveStatus> st(flat.size());
      flatScalar += prepareSegments(flat.data(), 0, flat.size(), frame, segmentSetupFrame(frame), out.data(), st.data());
    }
    EXPECT_GT(tally.compared, tally.visible * 99 / 100);
    EXPECT_GT(tally.stations, tally.visible * 9 / 10);  // the exact path shades them with stations
    EXPECT_LE(tally.scalar, flatScalar + tally.segments / 100) << "turning segments left the batches";
    std::printf("deferred %d: %zu segments, %zu to the exact path (%zu not turning), %d visible, %d with stations\n",
                int(deferred), tally.segments, tally.scalar, flatScalar, tally.visible, tally.stations);
  }
}

// Segments so thin against a pixel that the prefilter stretches their covariance past
// kMaxStretch sigma_r (the dragon's far contour segments: 6% of them before) are clamped in the
// batches as the exact path clamps them (segment::clampEigen), not handed to it.
TEST(SegmentPrepare, StretchedSegmentsStayInTheBatches) {
  Tally tally;
  for (float dist : {3.0f, 20.0f}) {
    const Vec3f eye = Vec3f(0.3f, 0.2f, 1).normalized() * dist;
    std::vector<Segment> segs = randomSegments(3000, eye, false, uint32_t(41 + int(dist)), true);
    for (Segment& s : segs) s.radius *= 1e-3f;  // 1e-6 .. 1e-3: a tiny fraction of a pixel
    const Camera cam = Camera::lookAt(eye, Vec3f::Zero(), Vec3f(0, 1, 0), 40, 320, 240, 0.05f, 1000);
    check(segs, cam, RenderOptions{}, false, tally);
  }
  EXPECT_GT(tally.compared, tally.visible * 99 / 100);
  EXPECT_GT(tally.visible, 500);
  EXPECT_LT(tally.scalar, size_t(tally.visible / 4)) << "stretched segments left the batches";
  std::printf("%zu segments, %zu to the exact path, %d visible\n", tally.segments, tally.scalar, tally.visible);
}

TEST(SegmentPrepare, UnusualInputGoesToTheExactPath) {
  // degenerate input the exact stages count (zero/NaN/infinite radius, NaN endpoints, zero length)
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f::Zero(), Vec3f(0, 1, 0), 40, 64, 64);
  RenderOptions o;
  const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
  Segment base;
  base.p0 = Vec3f(-0.1f, 0, 0), base.p1 = Vec3f(0.1f, 0, 0), base.normal = Vec3f(0, 0, 1), base.radius = 0.02f;
  std::vector<Segment> segs(8, base);
  segs[1].radius = 0;
  segs[2].radius = NAN;
  segs[3].radius = INFINITY;
  segs[4].p0.x() = NAN;
  segs[5].p1 = segs[5].p0;
  segs[6].normal = Vec3f::Zero();  // no normal: the strip facing the viewer
  segs[7].normal = Vec3f(1, 0, 0);  // along the segment: no usable normal either
  std::vector<PreparedSegment> out(segs.size()), ref(segs.size());
  std::vector<PrimitiveStatus> st(segs.size());
  prepareSegments(segs.data(), 0, segs.size(), frame, segmentSetupFrame(frame), out.data(), st.data());
  for (size_t i = 0; i < segs.size(); ++i) {
    const PrimitiveStatus x = prepareSegment(segs[i], uint32_t(i), frame, ref[i]);
    EXPECT_EQ(int(st[i]), int(x)) << i;
    if (visible(x)) {
      const Vec2f mid = cam.project(cam.toCamera(0.5f * (segs[i].p0 + segs[i].p1))).head<2>();
      EXPECT_EQ(agree(out[i], ref[i], mid), "") << i;
    }
  }
  EXPECT_EQ(st[0], PrimitiveStatus::Drawn);
  for (int i : {1, 2, 3, 4, 5}) EXPECT_EQ(st[size_t(i)], PrimitiveStatus::Degenerate) << i;
  EXPECT_EQ(st[6], PrimitiveStatus::Drawn);
}

TEST(SegmentPrepare, BatchesAgreeWithTheExactPathOnEveryTarget) {
  // how the batches load their input depends on the target (512-bit vectors: Segment blocks
  // transposed; else lane-by-lane copies), and their arithmetic on its vector length: on every
  // target the machine runs, every record agrees with the exact path's
  const Vec3f eye = Vec3f(0.3f, 0.2f, 1).normalized() * 3.0f;
  const Camera cam = Camera::lookAt(eye, Vec3f::Zero(), Vec3f(0, 1, 0), 40, 320, 240, 0.05f, 1000);
  RenderOptions o;
  o.material.specular = 0.5f;
  int targets = 0;
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    for (bool turning : {false, true}) {
      Tally tally;
      check(randomSegments(2000, eye, true, uint32_t(21 + turning), turning), cam, o, true, tally);
      EXPECT_GT(tally.compared, 300) << "target " << target;
      EXPECT_GT(tally.compared, tally.visible * 99 / 100) << "target " << target;
      if (turning) { EXPECT_GT(tally.stations, tally.visible / 2) << "target " << target; }
    }
    ++targets;
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(targets, 0);
}

TEST(SegmentPrepare, BatchInputIsTheSegmentsFields) {
  // segmentLoad (512-bit vectors: 4 x 4 Segment blocks transposed) gives the batch the fields the
  // lane-by-lane copy gives it, bit for bit, the colours as FrameContext::primitiveColor, for a
  // batch not a multiple of the vector length; on targets without it, it declines
  const Vec3f eye(3.1f, -7.3f, 11.7f);
  const Camera cam = Camera::lookAt(eye, Vec3f(0.2f, 0.1f, -0.3f), Vec3f(0, 1, 0), 40, 320, 240);
  std::vector<Segment> segs = randomSegments(2 * detail::kSegmentBatch, eye, true, 13);
  for (size_t j = 0; j < segs.size(); ++j) segs[j].color = Color(0.01f * float(j), 0.5f, 1 - 0.003f * float(j), 0.25f + 0.001f * float(j));
  std::vector<PreparedSegment> out(segs.size());
  int loaded = 0;
  for (int variant = 0; variant < 3; ++variant) {
    RenderOptions o;
    o.defaultColor = Color(0.3f, 0.6f, 0.9f, 0.8f);
    if (variant == 2) o.alphaOverride = 0.4f;
    FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1.5f}, /*modelHasColors=*/variant != 1);
    frame.endpointNormals = variant != 2;
    const detail::SegmentSetupFrame F = segmentSetupFrame(frame);
    for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
      hwy::SetSupportedTargetsForTest(target);
      for (int n : {detail::kSegmentBatch, 37}) {
        detail::SegmentSetupBatch b;
        const Segment* in = segs.data() + 5;
        if (!detail::segmentLoad(F, b, in, n, out.data())) continue;
        ++loaded;
        for (int j = 0; j < n; ++j) {
          const Segment& s = in[j];
          const Color c = frame.primitiveColor(s.color);
          const float want[] = {s.p0.x(), s.p0.y(), s.p0.z(), s.p1.x(), s.p1.y(), s.p1.z(), s.normal.x(), s.normal.y(),
                                s.normal.z(), s.radius, c.x(), c.y(), c.z(), c.w()};
          const float got[] = {b.p0x[j], b.p0y[j], b.p0z[j], b.p1x[j], b.p1y[j], b.p1z[j], b.wx[j], b.wy[j],
                               b.wz[j], b.radius[j], b.cr[j], b.cg[j], b.cb[j], b.ca[j]};
          for (int k = 0; k < 14; ++k) EXPECT_EQ(got[k], want[k]) << "field " << k << " lane " << j << " variant " << variant;
          if (frame.endpointNormals) {
            const float wantN[] = {s.normal0.x(), s.normal0.y(), s.normal0.z(), s.normal1.x(), s.normal1.y(), s.normal1.z()};
            const float gotN[] = {b.m0x[j], b.m0y[j], b.m0z[j], b.m1x[j], b.m1y[j], b.m1z[j]};
            for (int k = 0; k < 6; ++k) EXPECT_EQ(gotN[k], wantN[k]) << "normal field " << k << " lane " << j;
          }
        }
      }
    }
    hwy::SetSupportedTargetsForTest(0);
  }
  if (hwy::SupportedTargets() & HWY_AVX3) {
    EXPECT_GT(loaded, 0);  // the AVX-512 code ran
  }
}

TEST(SegmentPrepare, BatchesTakeCameraSpaceAsToCameraRoundsIt) {
  // segmentToCamera's world -> camera transform rounds as Camera::toCamera and rotation() products
  // do (the exact path's input: a short segment far away keeps its direction), bit for bit, on
  // every SIMD target the machine runs; the smooth flags and plane normals as stage 1 takes them
  const Vec3f eye(3.1f, -7.3f, 11.7f);
  const Camera cam = Camera::lookAt(eye, Vec3f(0.2f, 0.1f, -0.3f), Vec3f(0, 1, 0), 40, 320, 240);
  RenderOptions o;
  FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1.5f});
  frame.endpointNormals = true;
  std::vector<Segment> segs = randomSegments(detail::kSegmentBatch, eye, true, 7);
  segs[3].normal = Vec3f::Zero();    // the plane normal from the endpoint normals
  segs[5].normal1 = Vec3f::Zero();   // not smooth
  segs[6].normal0.x() = NAN;         // not smooth
  const detail::SegmentSetupFrame F = segmentSetupFrame(frame);
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    detail::SegmentSetupBatch b;
    const int n = detail::kSegmentBatch;
    for (int j = 0; j < n; ++j) {
      const Segment& s = segs[size_t(j)];
      b.p0x[j] = s.p0.x(), b.p0y[j] = s.p0.y(), b.p0z[j] = s.p0.z();
      b.p1x[j] = s.p1.x(), b.p1y[j] = s.p1.y(), b.p1z[j] = s.p1.z();
      b.wx[j] = s.normal.x(), b.wy[j] = s.normal.y(), b.wz[j] = s.normal.z(), b.radius[j] = s.radius;
      b.m0x[j] = s.normal0.x(), b.m0y[j] = s.normal0.y(), b.m0z[j] = s.normal0.z();
      b.m1x[j] = s.normal1.x(), b.m1y[j] = s.normal1.y(), b.m1z[j] = s.normal1.z();
      b.cr[j] = b.cg[j] = b.cb[j] = b.ca[j] = 1;
    }
    detail::segmentToCamera(F, b, n);
    for (int j = 0; j < n; ++j) {
      const Segment& s = segs[size_t(j)];
      const Vec3f c0 = cam.toCamera(s.p0), c1 = cam.toCamera(s.p1);
      const bool smooth = s.normal0.allFinite() && s.normal1.allFinite() && s.normal0.squaredNorm() > 0 &&
                          s.normal1.squaredNorm() > 0;
      const Vec3f w = cam.rotation() * (smooth && !(s.normal.squaredNorm() > 0) ? Vec3f(s.normal0 + s.normal1) : s.normal);
      auto same = [&](const float* x, const float* y, const float* z, const Vec3f& v, const char* what) {
        EXPECT_TRUE(x[j] == v.x() && y[j] == v.y() && z[j] == v.z()) << what << " " << j << " target " << target;
      };
      same(b.p0x, b.p0y, b.p0z, c0, "p0");
      same(b.p1x, b.p1y, b.p1z, c1, "p1");
      same(b.wx, b.wy, b.wz, w, "plane normal");
      EXPECT_EQ(b.smooth[j] > 0, smooth) << j;
      if (smooth) {
        same(b.m0x, b.m0y, b.m0z, Vec3f(cam.rotation() * s.normal0), "normal0");
        same(b.m1x, b.m1y, b.m1z, Vec3f(cam.rotation() * s.normal1), "normal1");
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

}  // namespace
}  // namespace linesurf

namespace linesurf {
TEST(SegmentPrepare, ChainsShareTheirEndpointsBitForBit) {
  // a helix traced as one chain (consecutive segments with bit-equal endpoints, as curvature and
  // contour lines store them), with endpoint normals and without: setting a shared endpoint up
  // once gives every record and status the bits of setting it up twice
  const Camera cam = Camera::lookAt(Vec3f(0.3f, -0.4f, 3), Vec3f::Zero(), Vec3f(0, 1, 0), 40, 256, 256);
  RenderOptions o;
  for (bool smooth : {false, true}) {
    FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
    frame.endpointNormals = smooth;
    std::vector<Segment> segs;
    Vec3f prev(0.8f, 0, -0.8f);
    for (int i = 1; i <= 1000; ++i) {
      const float t = 0.02f * float(i);
      const Vec3f p(0.8f * std::cos(t), 0.8f * std::sin(t), -0.8f + 0.0016f * float(i));
      Segment s;
      s.p0 = prev, s.p1 = p, s.radius = 0.015f;
      s.normal = Vec3f(0.3f * std::cos(t), 0.3f * std::sin(t), 1);
      s.normal0 = s.normal, s.normal1 = Vec3f(0.3f * std::cos(t + 0.02f), 0.3f * std::sin(t + 0.02f), 1);
      if (i % 97 == 0) s.p0.x() += 1e-3f;  // a few breaks in the chain
      segs.push_back(s);
      prev = p;
    }
    std::vector<PreparedSegment> a(segs.size()), b(segs.size());
    std::vector<PrimitiveStatus> sa(segs.size()), sb(segs.size());
    detail::SegmentSetupFrame setup = segmentSetupFrame(frame);
    ASSERT_TRUE(setup.shareChainEnds);
    prepareSegments(segs.data(), 0, segs.size(), frame, setup, a.data(), sa.data());
    setup.shareChainEnds = false;
    prepareSegments(segs.data(), 0, segs.size(), frame, setup, b.data(), sb.data());
    size_t drawn = 0;
    for (size_t i = 0; i < segs.size(); ++i) {
      ASSERT_EQ(int(sa[i]), int(sb[i])) << i;
      if (!visible(sa[i])) continue;
      ++drawn;
      const char* x = reinterpret_cast<const char*>(&a[i]);
      const char* y = reinterpret_cast<const char*>(&b[i]);
      // the record's bytes after `extra` (its first 8, not written in the common case)
      EXPECT_EQ(std::memcmp(x + 8, y + 8, 16 * size_t(detail::kRecordChunks) - 8), 0) << i << " smooth " << smooth;
    }
    EXPECT_GT(drawn, segs.size() / 3);
  }
}
}  // namespace linesurf
