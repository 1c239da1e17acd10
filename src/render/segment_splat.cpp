// Object-space EWA splatting of line segments, thesis §5 (see segment_splat.h for the method and
// the stages, docs/segment-splatting.md). The evaluations themselves are in segment_filter.cpp
// (ScreenSpace closed form, Reference quadrature) and segment_approx.cpp (§5.2.3, Approx
// quadrilaterals); the SIMD rows of the common case in segment_rows.cpp.
#include "segment_splat.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <new>

#include "segment_approx.h"
#include "segment_filter.h"
#include "splat_rules.h"

namespace linesurf {

namespace {

using segment::Mat2d;
using segment::Vec2dd;
// Same limits as point splats (splat_rules.h): strips seen closer to edge-on than
// kMinFacing everywhere are culled, and no kernel reaches farther than kMaxStretch sigma_r.
constexpr double kMinFacing = detail::kMinFacing;
constexpr double kMaxStretch = detail::kMaxStretch;
using segment::kPieceTolerance;
using segment::kShortSegment;
using segment::kStationTurn;

// --- prepare, stage 1: the strip in camera space ------------------------------------------

// p0, the unit axes (e along, n the plane's normal facing the viewer, s = e x n across) and
// the length, in double: the construction must not lose short segments.
struct Strip {
  Vec3d c0 = Vec3d::Zero(), e = Vec3d::Zero(), n = Vec3d::Zero(), s = Vec3d::Zero();
  double L = 0;
  bool smooth = false;  ///< usable endpoint normals shade it (smooth line models)
};

// Culling (degenerate input, back faces, grazing, beyond near/far) and the model-view
// transform with the local parameterisation (§6.2.2): b axis s = e x n, the normal made
// perpendicular to e.
PrimitiveStatus stripFrame(const Segment& seg, const FrameContext& frame, Strip& st) {
  const Camera& cam = frame.cam();
  const RenderOptions& opt = frame.opt();
  if (!(seg.radius > 0) || !std::isfinite(seg.radius) || !seg.p0.allFinite() || !seg.p1.allFinite() ||
      !seg.normal.allFinite())
    return PrimitiveStatus::Degenerate;
  const Vec3d c0 = cam.toCamera(seg.p0).cast<double>(), c1 = cam.toCamera(seg.p1).cast<double>();
  const double L = (c1 - c0).norm();
  if (!(L > 1e-6 * seg.radius) || !std::isfinite(L)) return PrimitiveStatus::Degenerate;
  const Vec3d e = (c1 - c0) / L;
  {  // cheap rejection by depth with the largest possible footprint
    const double reach = double(opt.cutoffRadius) * opt.reconstructionScale * seg.radius * kMaxStretch;
    const double dmin = std::min(-c0.z(), -c1.z()) - reach, dmax = std::max(-c0.z(), -c1.z()) + reach;
    if (dmax < cam.nearDepth() || dmin > cam.farDepth()) return PrimitiveStatus::Outside;
  }
  st.smooth = frame.endpointNormals && seg.normal0.allFinite() && seg.normal1.allFinite() &&
              seg.normal0.squaredNorm() > 0 && seg.normal1.squaredNorm() > 0;
  const Vec3f planeNormal = st.smooth && !(seg.normal.squaredNorm() > 0) ? Vec3f(seg.normal0 + seg.normal1) : seg.normal;
  Vec3d n = (cam.rotation() * planeNormal).cast<double>();
  n -= n.dot(e) * e;
  if (!(n.norm() > 1e-3)) {  // no (usable) normal: the strip through the segment facing the viewer
    const Vec3d toEye = -(c0 + 0.5 * L * e);
    n = toEye - toEye.dot(e) * e;
    if (!(n.norm() > 0)) n = std::abs(e.x()) < 0.9 ? Vec3d(Vec3d::UnitX().cross(e)) : Vec3d(Vec3d::UnitY().cross(e));
  }
  n.normalize();
  // back-face culling: the strip's plane faces the eye on one side only (sign constant along it)
  double D = -n.dot(c0);
  if (D < 0) {
    if (opt.backfaceCulling) return PrimitiveStatus::Culled;
    n = -n;
    D = -D;
  }
  // grazing everywhere: the largest |cos| is at the point nearest to the eye
  const double t = std::clamp(-c0.dot(e), 0.0, L);
  const double dist = (c0 + t * e).norm();
  if (!(dist > 0) || D / dist < kMinFacing) return PrimitiveStatus::Culled;
  st.c0 = c0;
  st.e = e;
  st.n = n;
  st.s = e.cross(n);
  st.L = L;
  return PrimitiveStatus::Drawn;
}

// --- prepare, stage 2: resampling covariance and footprint (§5.1.2) -----------------------

struct Footprint {
  Mat2d M0, M1;                       ///< covariance at p0 and p1
  SegmentPiece first;                 ///< the first (K = 1: only) ScreenSpace sub-segment
  int K = 1;                          ///< sub-segments
  double aMin = 0, aMax = 0, bMax = 0;  ///< footprint box in plane coordinates
};

// The covariance at both ends and the middle decides the number of sub-segments K (where M
// changes by more than kPieceTolerance); K > 1 keeps its pieces in out.extra.
void footprint(const Strip& st, double radius, const FrameContext& frame, Footprint& fp, PreparedSegment& out) {
  const RenderOptions& opt = frame.opt();
  const double R = opt.cutoffRadius, sigmaR = double(opt.reconstructionScale) * radius, h = radius;
  const double Vh = opt.prefilterVariance, f = frame.cam().focalPixels(), L = st.L;
  auto covAt = [&](double a) { return segment::resamplingCovariance(st.c0 + a * st.e, st.e, st.s, sigmaR, Vh, f); };
  fp.M0 = covAt(0);
  fp.M1 = covAt(L);
  // M's second-order change along a segment short against its depth is below rounding of the
  // piece test: the mean of the ends stands for the middle
  const double dMin = std::min(-st.c0.z(), -(st.c0.z() + L * st.e.z()));
  const Mat2d Mmid = L < kShortSegment * dMin ? Mat2d(0.5 * (fp.M0 + fp.M1)) : covAt(0.5 * L);
  const double scale = std::min(fp.M0.norm(), fp.M1.norm());
  const double change = std::max((fp.M1 - fp.M0).norm(), 4 * (Mmid - 0.5 * (fp.M0 + fp.M1)).norm());
  const int K = int(std::clamp(std::ceil(change / (kPieceTolerance * scale)), 1.0, double(kMaxSegmentPieces)));
  fp.K = K;
  fp.aMin = 0, fp.aMax = L, fp.bMax = 0;
  auto extend = [&](const SegmentPiece& p, const Mat2d& M) {
    fp.aMin = std::min(fp.aMin, double(p.a0) - double(p.reach));
    fp.aMax = std::max(fp.aMax, double(p.a1) + double(p.reach));
    fp.bMax = std::max(fp.bMax, R * std::sqrt(M(1, 1)));
  };
  if (K == 1) {
    fp.first = segment::makePiece(0, L, Mmid, fp.M0, fp.M1, h, R);
    extend(fp.first, Mmid);
    return;
  }
  SegmentExtra& x = extraOf(out);
  x.pieces.resize(K);
  x.pieceInvLength = float(K / L);
  x.pieceMaxReach = 0;
  Mat2d lo = fp.M0;
  for (int k = 0; k < K; ++k) {
    const double a0 = L * k / K, a1 = L * (k + 1) / K;
    const Mat2d hi = k + 1 == K ? fp.M1 : 2 * (k + 1) == K ? Mmid : covAt(a1);
    const Mat2d M = covAt(0.5 * (a0 + a1));
    x.pieces[k] = segment::makePiece(a0, a1, M, lo, hi, h, R);
    x.pieceMaxReach = std::max(x.pieceMaxReach, x.pieces[k].reach);
    extend(x.pieces[k], M);
    lo = hi;
  }
  fp.first = x.pieces[0];
}

// --- prepare, stage 3: the method's own data ----------------------------------------------

// Reference nodes or Approx quadrilaterals (which replace the footprint box); an Approx
// construction that fails falls back to ScreenSpace (counted).
SegmentMethod methodData(const Strip& st, double radius, const FrameContext& frame, Footprint& fp, PreparedSegment& out) {
  const RenderOptions& opt = frame.opt();
  const double R = opt.cutoffRadius, sigmaR = double(opt.reconstructionScale) * radius;
  switch (opt.segmentMethod) {
    case SegmentMethod::ScreenSpace: return SegmentMethod::ScreenSpace;
    case SegmentMethod::Reference:
      segment::referenceNodes(st.L, sigmaR, radius, R, st.c0, st.e, st.s, opt.prefilterVariance, frame.cam().focalPixels(),
                              extraOf(out), fp.aMin, fp.aMax, fp.bMax);
      return SegmentMethod::Reference;
    case SegmentMethod::Approx:
      if (segment::buildApprox(fp.M0, fp.M1, st.L, R, radius, extraOf(out), fp.aMin, fp.aMax, fp.bMax))
        return SegmentMethod::Approx;
      out.fallback = true;
      return SegmentMethod::ScreenSpace;
  }
  return SegmentMethod::ScreenSpace;
}

// --- prepare, stage 4: screen bounds -------------------------------------------------------

// Frustum test of the footprint box (a in [aMin, aMax], b in [-bMax, bMax]), clipping against
// the near/far planes, pixel bounds and the projected box for the row spans.
PrimitiveStatus screenBounds(const Strip& st, const Footprint& fp, const FrameContext& frame, PreparedSegment& out,
                             bool& depthClipped) {
  const Camera& cam = frame.cam();
  const Vec3d& c0 = st.c0;
  const Vec3d box[4] = {c0 + fp.aMin * st.e - fp.bMax * st.s, c0 + fp.aMax * st.e - fp.bMax * st.s,
                        c0 + fp.aMax * st.e + fp.bMax * st.s, c0 + fp.aMin * st.e + fp.bMax * st.s};
  Vec3f boxf[4];
  for (int i = 0; i < 4; ++i) boxf[i] = box[i].cast<float>();
  bool inDepth = true;
  for (const Vec3f& q : boxf) inDepth &= -q.z() >= cam.nearDepth() && -q.z() <= cam.farDepth();
  // In front of the eye the side planes sort the corners as their projections sort against the
  // viewport, so the pixel bounds below test them; otherwise every frustum plane is tested.
  for (size_t k = 0; k < frame.frustum.size() && !inDepth; ++k) {
    const Vec4f& pl = frame.frustum[k];
    bool allOut = true;
    for (const Vec3f& q : boxf)
      if (pl.head<3>().dot(q) + pl.w() >= 0) {
        allOut = false;
        break;
      }
    if (allOut) return PrimitiveStatus::Outside;
  }
  float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  depthClipped = false;
  if (inDepth) {  // the common case: the projected corners bound the box (and give the row spans)
    for (int i = 0; i < 4; ++i) {
      out.screenQuad[i] = cam.project(boxf[i]).head<2>();
      x0 = std::min(x0, out.screenQuad[i].x()), x1 = std::max(x1, out.screenQuad[i].x());
      y0 = std::min(y0, out.screenQuad[i].y()), y1 = std::max(y1, out.screenQuad[i].y());
    }
  } else if (!detail::clippedScreenBounds(cam, boxf, 4, x0, y0, x1, y1, depthClipped)) {
    return PrimitiveStatus::Outside;
  }
  const PixelRect view{0, 0, cam.width(), cam.height()};
  auto pix = [](float v) { return int(std::floor(std::clamp(v, -1e8f, 1e8f) - 0.5f)) + 1; };
  const PixelRect bb{pix(x0), pix(y0), pix(x1), pix(y1)};
  out.bounds = bb.intersect(view);
  if (out.bounds.empty()) return PrimitiveStatus::Outside;
  out.useSpans = inDepth;
  for (int i = 0; i < 4 && inDepth; ++i) out.useSpans &= out.screenQuad[i].allFinite();
  const bool sideClipped = out.bounds.x0 != bb.x0 || out.bounds.y0 != bb.y0 || out.bounds.x1 != bb.x1 ||
                           out.bounds.y1 != bb.y1;
  return depthClipped || sideClipped ? PrimitiveStatus::Clipped : PrimitiveStatus::Drawn;
}

// --- prepare, stage 5: per-pixel constants ------------------------------------------------

// Ray through pixel (px, py) at depth 1: r = ((px - cx)/f, -(py - cy)/f, -1); the plane
// n.(P - o) = 0 is hit at depth t = (n.o)/(n.r), a = t (e.r) - e.o, b = t (s.r) - s.o.
void rasterConstants(const Strip& st, const Footprint& fp, double radius, const FrameContext& frame, bool depthClipped,
                     PreparedSegment& out) {
  detail::SegmentRaster& k = out.raster;
  const Camera& cam = frame.cam();
  const Vec3f o = st.c0.cast<float>(), e = st.e.cast<float>(), s = st.s.cast<float>(), n = st.n.cast<float>();
  const float no = n.dot(o);
  auto scaled = [](float c, detail::Affine2 g) { return detail::Affine2{c * g.dx, c * g.dy, c * g.c}; };
  k.N = detail::rayDot(cam, n);
  k.A = scaled(no, detail::rayDot(cam, e));
  k.B = scaled(no, detail::rayDot(cam, s));
  k.depthNum = no;
  k.a0 = e.dot(o);
  k.b0 = s.dot(o);
  k.length = float(st.L);
  k.R2 = frame.cutoffQ;
  k.aMin = float(fp.aMin), k.aMax = float(fp.aMax), k.bMax = float(fp.bMax);
  const SegmentPiece& p = fp.first;
  k.skew = p.skew, k.across = p.across, k.invM00 = p.invM00, k.k = p.k, k.erfScale = p.erfScale;
  k.scale0 = p.scale0, k.slope = p.slope;
  // Z^3 threshold: depth half-extent of the endpoint cutoff ellipses plus the radius (§6.2.3.2)
  const double R = frame.opt().cutoffRadius;
  const Vec2dd g(st.e.z(), st.s.z());
  k.zThreshold0 = frame.zThreshold(float(R * std::sqrt(g.dot(fp.M0 * g)) + radius));
  k.zThreshold1 = frame.zThreshold(float(R * std::sqrt(g.dot(fp.M1 * g)) + radius));
  k.nearD = cam.nearDepth(), k.farD = cam.farDepth();
  k.tailB = float(detail::kTailDisc * R * double(frame.opt().reconstructionScale) * radius);
  k.clipDepth = depthClipped;
  k.pieceCount = fp.K;
  if (fp.K > 1) {
    const SegmentExtra& x = *out.extra;
    k.pieces = x.pieces.data();
    k.pieceInvLength = x.pieceInvLength;
    k.pieceMaxReach = x.pieceMaxReach;
  }
}

// --- prepare, stage 6: shading --------------------------------------------------------------

// Gouraud colours along the segment (§6.2.2), or the albedo when lighting is deferred;
// smooth line models interpolate the endpoint normals. The common cases keep the colour
// linear in u (two stations) and need no per-fragment lighting.
void shading(const Segment& seg, const Strip& st, int K, const FrameContext& frame, PreparedSegment& out) {
  const Camera& cam = frame.cam();
  const RenderOptions& opt = frame.opt();
  const Vec3f n = st.n.cast<float>();
  out.smooth = st.smooth;
  if (st.smooth) {  // endpoint shading normals, on the side of the (possibly flipped) plane normal
    Vec3f m0 = (cam.rotation() * seg.normal0).normalized(), m1 = (cam.rotation() * seg.normal1).normalized();
    if (n.dot(m0 + m1) < 0) {
      m0 = -m0;
      m1 = -m1;
    }
    out.n0 = m0;
    out.dn = m1 - m0;
  }
  auto normalAt = [&](float u) -> Vec3f {
    if (!st.smooth) return n;
    const Vec3f m = out.n0 + u * out.dn;
    const float len = m.norm();
    return len > 0 ? Vec3f(m / len) : n;
  };
  const Color col = frame.primitiveColor(seg.color);
  const Vec3f albedo = col.head<3>();
  const Vec3f n0 = normalAt(0);
  setBaseAttributes(out, col, n0);
  float* a = out.attr;
  const bool textured = frame.texture != nullptr;
  int S = 0;  // stations - 1 (Gouraud)
  const float cosTurn = st.smooth ? normalAt(0).dot(normalAt(1)) : 1.0f;
  const bool turns = cosTurn < std::cos(kStationTurn);
  if (!opt.perPixelLighting) {
    S = K;
    if (turns) {  // one station per kStationTurn the shading normal turns
      S = stationIntervals(std::acos(std::clamp(cosTurn, -1.0f, 1.0f)), K);
    }
  }
  const Vec3f c0 = st.c0.cast<float>();
  auto pointAt = [&](int k) { return (st.c0 + (st.L * k / S) * st.e).cast<float>(); };
  if (!textured && S <= 1 && !turns) {
    out.shade = st.smooth ? SegmentShade::Smooth : S == 0 ? SegmentShade::Constant : SegmentShade::Linear;
    if (S == 1) {
      const Vec3f k0 = frame.shade(albedo, n0, c0), k1 = frame.shade(albedo, normalAt(1), pointAt(1));
      a[Z3Tile::kR] = k0.x(), a[Z3Tile::kG] = k0.y(), a[Z3Tile::kB] = k0.z();
      out.dc = k1 - k0;
    }
    return;
  }
  out.shade = SegmentShade::Stations;
  if (!textured) {  // the lit colours themselves
    float* colour = untexturedStations(out, seg, S);
    for (int k = 0; S > 0 && k <= S; ++k) {
      const Vec3f c = frame.shade(albedo, normalAt(float(k) / float(S)), pointAt(k));
      for (int ch = 0; ch < 3; ++ch) colour[ch * (S + 1) + k] = c[ch];
    }
    return;
  }
  SegmentExtra& x = stationsExtra(out, seg, textured, S);
  for (int k = 0; S > 0 && k <= S; ++k) {
    const Vec3f nf = normalAt(float(k) / float(S));
    const Vec3f p = pointAt(k);
    x.specular.push_back(frame.shade(Vec3f::Zero(), nf, p));
    x.diffuse.push_back(frame.shade(Vec3f::Ones(), nf, p) - x.specular.back());
  }
}

}  // namespace

PrimitiveStatus prepareSegment(const Segment& seg, uint32_t index, const FrameContext& frame, PreparedSegment& out) {
  out.index = index;
  out.bounds = {};
  out.fallback = false;
  out.smooth = false;
  out.stationCount = -1;
  resetExtra(out.extra);
  Strip st;
  const PrimitiveStatus culled = stripFrame(seg, frame, st);
  if (culled != PrimitiveStatus::Drawn) return culled;
  Footprint fp;
  footprint(st, seg.radius, frame, fp, out);
  out.method = methodData(st, seg.radius, frame, fp, out);
  bool depthClipped = false;
  const PrimitiveStatus status = screenBounds(st, fp, frame, out, depthClipped);
  if (status != PrimitiveStatus::Drawn && status != PrimitiveStatus::Clipped) {
    out.bounds = {};
    return status;
  }
  rasterConstants(st, fp, seg.radius, frame, depthClipped, out);
  shading(seg, st, fp.K, frame, out);
  return status;
}

}  // namespace linesurf
