// Object-space EWA splatting of line segments, thesis §5 (see linesurf/render/segment_splat.h
// for the method, segment_splat.h for the stages, docs/segment-splatting.md). The evaluations
// themselves (ScreenSpace closed form, Reference quadrature, Approx quadrilaterals) are in
// segment_methods.cpp; the SIMD rows of the common case in splat_rows.cpp.
#include "segment_splat.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <new>

#include "detail/splat_math.h"
#include "segment_methods.h"

namespace linesurf {

namespace {

using segment::Mat2d;
using segment::Vec2dd;
// Same limits as point splats (detail/splat_math.h): strips seen closer to edge-on than
// kMinFacing everywhere are culled, and no kernel reaches farther than kMaxStretch sigma_r.
constexpr double kMinFacing = detail::kMinFacing;
constexpr double kMaxStretch = detail::kMaxStretch;
using segment::kPieceTolerance;
using segment::kShortSegment;
// Rasterisation visits the pixel centres within this distance (pixels) of the projected footprint
// box: the projection and the per-pixel ray-plane intersection differ by rounding only.
constexpr float kSpanSlack = 0.05f;
using segment::kStationTurn;
// Rectangles of at most this many pixels are rasterised whole (as point splats are), larger ones
// in the rows' spans of the projected footprint box: a span costs its set-up, a pixel outside the
// footprint only its share of a SIMD vector.
constexpr int kWholeRectArea = 96;

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

// --- level of detail: a short segment as one elliptical point splat (beyond the thesis) -------

bool segmentLodPoint(const PreparedSegment& sp, const FrameContext& frame, float maxLambda, const PointSlots& out) {
  const detail::SegmentRaster& k = sp.raster;
  if (sp.method != SegmentMethod::ScreenSpace || sp.fallback || k.pieceCount != 1 || k.clipDepth || !sp.useSpans ||
      sp.shade == SegmentShade::Stations || !(k.invM00 > 0) || !(k.across > 0) || !(k.length > 0))
    return false;
  // lambda^2 = l^2 m00 = l^2 / invM00
  const float l = k.length, invM00 = k.invM00, across = k.across, skew = k.skew;
  if (!(l * l <= maxLambda * maxLambda * invM00)) return false;
  // mass, mean and variance of the scale w(tau) = scale0 + slope tau over [0, l] (one division):
  // with D = scale0 + slope l / 2, mass = l D, mean = l (scale0 / 2 + slope l / 3) / D,
  // E[tau^2] = l^2 (scale0 / 3 + slope l / 4) / D; the scale may change by at most half along
  const float sl = k.slope * l, D = k.scale0 + 0.5f * sl;
  if (!(k.scale0 > 0) || !(std::abs(sl) <= 0.5f * k.scale0)) return false;
  const float invD = 1 / D, mass = l * D;
  const float um = (0.5f * k.scale0 + sl / 3) * invD;  // the mean along, as a fraction of l
  const float var = l * l * std::max(0.0f, (k.scale0 / 3 + 0.25f * sl) * invD - um * um);
  const float am = um * l;
  // Sigma^-1 = L L^T: l00^2 = m00 / (1 + var m00) = 1 / (invM00 + var), l11^2 = across; the
  // weight scale keeps the mass: mass sqrt(det Sigma^-1 / det M^-1) = mass sqrt(invM00) l00
  const float l00 = 1 / std::sqrt(invM00 + var), l11 = std::sqrt(across);
  // the cutoff ellipse's box in plane coordinates (a in am +- R sqrt(Sigma_aa), Sigma_aa = invM00 +
  // skew^2 / across + var; |b| <= R sqrt(M_bb) = R / l11) inside the segment's footprint box, which
  // lies in front of the eye within near / far (the point rows clip no depth here): then the
  // projected ellipse is bounded and its box bounds it
  const float R2 = frame.cutoffQ;
  const float lo = am - k.aMin, hi = k.aMax - am, tol = 1e-3f * (k.aMax - k.aMin);
  const float reach = std::min(lo, hi) + tol;
  if (!(reach > 0) || R2 * ((invM00 + var) * across + skew * skew) > reach * reach * across ||
      R2 > k.bMax * k.bMax * across * (1 + 2e-5f))
    return false;
  // s N = l00 (A + skew B - (a0 + am + skew b0) N), t N = l11 (B - b0 N), in double: the terms cancel
  const double ca = double(k.a0) + double(am) + double(skew) * double(k.b0);
  auto affine = [](double cA, const detail::Affine2& A, double cB, const detail::Affine2& B, double cN,
                   const detail::Affine2& N) {
    return detail::Affine2{float(cA * A.dx + cB * B.dx + cN * N.dx), float(cA * A.dy + cB * B.dy + cN * N.dy),
                           float(cA * A.c + cB * B.c + cN * N.c)};
  };
  const detail::Affine2 S = affine(l00, k.A, double(l00) * skew, k.B, -double(l00) * ca, k.N);
  const detail::Affine2 T = affine(0, k.A, l11, k.B, -double(l11) * k.b0, k.N);
  double x0, y0, x1, y1;
  if (!detail::conicBounds(S, T, k.N, R2, x0, y0, x1, y1)) return false;
  bool cut = false;
  const PixelRect bounds = detail::pixelBounds(frame.cam(), x0, y0, x1, y1, cut).intersect(sp.bounds);
  if (bounds.empty()) return false;
  PreparedPoint& hot = *new (out.hot) PreparedPoint;
  *new (out.bounds) PixelRect = bounds;
  PointCold& cold = *new (out.cold) PointCold;
  hot.N = k.N, hot.S = S, hot.T = T;
  hot.depthNum = k.depthNum;
  hot.setWeightScale(mass * std::sqrt(invM00) * l00, false);
  hot.zThreshold = 0.5f * (k.zThreshold0 + k.zThreshold1);
  const float* a = sp.attr;
  for (int c = 0; c < 3; ++c) hot.color[c] = a[Z3Tile::kR + c] + um * sp.dc[c];
  hot.color[3] = a[Z3Tile::kA];
  Vec3f n(a[Z3Tile::kNx], a[Z3Tile::kNy], a[Z3Tile::kNz]);
  if (sp.shade == SegmentShade::Smooth) {
    const Vec3f m = sp.n0 + 0.5f * sp.dn;
    if (m.squaredNorm() > 0) n = m.normalized();
  }
  cold.normal[0] = n.x(), cold.normal[1] = n.y(), cold.normal[2] = n.z();
  cold.index = sp.index;
  if (PreparedPoint::gouraud(bounds, frame.opt().perPixelLighting)) {
    // the segment's colour, linear in a: a - am = s / l00 - skew t / l11
    PointGouraud& gr = *new (out.gouraud) PointGouraud;
    gr.C0 = Vec3f(hot.color[0], hot.color[1], hot.color[2]);
    gr.Cs = sp.dc * (1 / (l * l00));
    gr.Ct = sp.dc * (-skew / (l * l11));
    gr.Cst = Vec3f::Zero();
  }
  return true;
}

// --- per-pixel weights (scalar path) ----------------------------------------------------------

namespace {

// The only sub-segment of a one-piece ScreenSpace segment, from the per-pixel constants.
SegmentPiece onlyPiece(const detail::SegmentRaster& k) {
  SegmentPiece p;
  p.a0 = 0, p.a1 = k.length;
  p.reach = INFINITY;  // the footprint box is tested before
  p.skew = k.skew, p.across = k.across, p.invM00 = k.invM00, p.k = k.k, p.erfScale = k.erfScale;
  p.scale0 = k.scale0, p.slope = k.slope;
  return p;
}

float weightAt(const PreparedSegment& sp, float a, float b) {
  const detail::SegmentRaster& k = sp.raster;
  if (std::abs(b) > k.bMax || a < k.aMin || a > k.aMax) return 0;
  switch (sp.method) {
    case SegmentMethod::ScreenSpace: {
      if (sp.pieceCount() == 1) {
        const SegmentPiece p = onlyPiece(k);
        return segment::screenSpaceWeight(&p, 1, 0, 0, a, b, k.R2);
      }
      const SegmentExtra& x = *sp.extra;
      return segment::screenSpaceWeight(x.pieces.data(), int(x.pieces.size()), x.pieceInvLength, x.pieceMaxReach, a,
                                        b, k.R2);
    }
    case SegmentMethod::Reference: return segment::referenceWeight(*sp.extra, a, b, k.R2);
    case SegmentMethod::Approx: return segment::approxWeight(*sp.extra, a, b);
  }
  return 0;
}

}  // namespace

float segmentWeightAt(const PreparedSegment& sp, const FrameContext&, const Vec2f& pixel) {
  const detail::SegmentRaster& k = sp.raster;
  if (!(k.length > 0)) return 0;
  const float nr = k.N.at(pixel.x(), pixel.y());
  if (!(nr < 0)) return 0;
  const float inr = 1.0f / nr;
  return weightAt(sp, k.A.at(pixel.x(), pixel.y()) * inr - k.a0, k.B.at(pixel.x(), pixel.y()) * inr - k.b0);
}

// --- rasterise -------------------------------------------------------------------------------

namespace {

// floor(v) for |v| < 2^31 (std::floor is a library call in the generic x86-64 build)
inline int floorInt(float v) {
  const int i = int(v);
  return i - (float(i) > v);
}

// The rows' spans of the projected footprint box (a convex quad): pixel centres of row y
// (py = y + 0.5) inside it, widened by kSpanSlack pixel against rounding (a centre farther out
// lies outside the footprint box, where the weight is zero).
struct QuadSpans {
  float ylo[4], yhi[4], xa[4], ya[4], slope[4];
  int edges = 0;
  bool full = false;  ///< no quad: whole rows
  explicit QuadSpans(const PreparedSegment& sp) {
    full = !sp.useSpans;
    for (int i = 0; i < 4 && !full; ++i) {
      const Vec2f& p = sp.screenQuad[i];
      const Vec2f& q = sp.screenQuad[(i + 1) % 4];
      if (p.y() == q.y()) continue;
      ylo[edges] = std::min(p.y(), q.y()), yhi[edges] = std::max(p.y(), q.y());
      xa[edges] = p.x(), ya[edges] = p.y();
      slope[edges] = (q.x() - p.x()) / (q.y() - p.y());
      ++edges;
    }
  }
  // [xb, xe) within r; false when the row misses the quad
  bool row(const PixelRect& r, float py, int& xb, int& xe) const {
    xb = r.x0, xe = r.x1;
    if (full) return true;
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < edges; ++i) {
      if (!(ylo[i] <= py && py < yhi[i])) continue;
      const float x = xa[i] + (py - ya[i]) * slope[i];
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    if (!(hi >= lo)) return false;
    xb = std::max(r.x0, -floorInt(-(std::max(lo, -1e8f) - 0.5f - kSpanSlack)));
    xe = std::min(r.x1, floorInt(std::min(hi, 1e8f) - 0.5f + kSpanSlack) + 1);
    return xe > xb;
  }
};

// The rows' spans a segment's rasterisation walks over r: the cutoff region's (detail::segmentSpans) when tight,
// else those of the footprint box, whole rows when the rectangle is small or the box is clipped.
template <class Emit>
void forEachRowSpan(const PreparedSegment& sp, const PixelRect& r, bool tight, Emit&& emit) {
  if (tight && sp.method == SegmentMethod::ScreenSpace) {
    detail::RowSpan rows[detail::kBlock];
    for (int y0 = r.y0; y0 < r.y1; y0 += detail::kBlock) {  // bands of at most kBlock rows
      const PixelRect band{r.x0, y0, r.x1, std::min(r.y1, y0 + detail::kBlock)};
      int n;
      if (sp.raster.pieceCount == 1) {
        const detail::SegmentRaster* one = &sp.raster;
        detail::segmentSpansBatch(&one, &band, 1, kSpanSlack, rows, detail::kBlock, &n);
      } else {
        n = detail::segmentSpans(sp.raster, band, kSpanSlack, rows);
      }
      if (n < 0) break;  // degenerate constants (the first band already): the box
      for (int i = 0; i < n; ++i) emit(rows[i].y, rows[i].x0, rows[i].x1);
      if (y0 + detail::kBlock >= r.y1) return;
    }
  }
  const bool whole = r.width() * r.height() <= kWholeRectArea || !sp.useSpans;
  const QuadSpans quad(sp);
  for (int y = r.y0; y < r.y1; ++y) {
    int xb = r.x0, xe = r.x1;
    if (!whole && !quad.row(r, float(y) + 0.5f, xb, xe)) continue;
    emit(y, xb, xe);
  }
}

// The blended attributes of a segment fragment at along-parameter u (Z3Tile::Attr).
struct FragmentAttributes {
  const PreparedSegment& sp;
  const FrameContext& frame;
  float attr[Z3Tile::kAttrs];
  float dn2 = 0;  ///< |n1 - n0|^2 (Smooth)
  FragmentAttributes(const PreparedSegment& s, const FrameContext& f) : sp(s), frame(f), dn2(s.dn.squaredNorm()) {
    std::copy(sp.attr, sp.attr + Z3Tile::kAttrs, attr);
  }
  void at(float u) {
    switch (sp.shade) {
      case SegmentShade::Constant: return;
      case SegmentShade::Linear: return linearColour(u);
      case SegmentShade::Smooth: {
        // n0 and n1 are unit and at most kStationTurn apart, so |n0 + u dn|^2 = 1 - x with
        // x = u (1 - u) |dn|^2 <= 0.0025: 1 / sqrt(1 - x) to 5e-9 by its series
        linearColour(u);
        const float x = u * (1 - u) * dn2, inv = 1 + x * (0.5f + 0.375f * x);
        attr[Z3Tile::kNx] = (sp.n0.x() + u * sp.dn.x()) * inv;
        attr[Z3Tile::kNy] = (sp.n0.y() + u * sp.dn.y()) * inv;
        attr[Z3Tile::kNz] = (sp.n0.z() + u * sp.dn.z()) * inv;
        return;
      }
      case SegmentShade::Stations: return stations(u);
    }
  }
  void linearColour(float u) {
    attr[Z3Tile::kR] = sp.attr[Z3Tile::kR] + u * sp.dc.x();
    attr[Z3Tile::kG] = sp.attr[Z3Tile::kG] + u * sp.dc.y();
    attr[Z3Tile::kB] = sp.attr[Z3Tile::kB] + u * sp.dc.z();
  }
  // several lighting stations or a texture (§5.2.4: uv interpolated between the endpoints)
  void stations(float u) {
    Vec3f c(sp.attr[Z3Tile::kR], sp.attr[Z3Tile::kG], sp.attr[Z3Tile::kB]);
    if (sp.stationCount >= 0) {  // untextured, the stations in the record
      if (sp.stationCount >= 2) c = piecewise(sp.stationColour, sp.stationCount, u);
      return stationsDone(c, u);
    }
    const SegmentExtra& x = *sp.extra;
    if (x.textured) {
      const Vec2f uv = x.uv0 + u * (x.uv1 - x.uv0);
      c = frame.texture->sampleBilinear(uv.x(), uv.y()).head<3>();
    }
    if (!x.colour.empty()) {  // untextured: the stations' colours, piecewise linear
      c = piecewise(x.colour.data(), x.stations, u);
    } else if (!x.diffuse.empty()) {
      const int n = int(x.diffuse.size());
      const float fs = u * float(n - 1);
      const int k = std::min(int(fs), n - 2);
      const float v = fs - float(k);
      const Vec3f dif = (1 - v) * x.diffuse[k] + v * x.diffuse[k + 1];
      const Vec3f spec = (1 - v) * x.specular[k] + v * x.specular[k + 1];
      c = c.cwiseProduct(dif) + spec;
    }
    stationsDone(c, u);
  }
  // the colour of n stations (channel ch of station k at colour[ch * n + k]) at u, piecewise linear
  static Vec3f piecewise(const float* colour, int n, float u) {
    const float fs = u * float(n - 1);
    const int k = std::min(int(fs), n - 2);
    const float v = fs - float(k);
    Vec3f c;
    for (int ch = 0; ch < 3; ++ch) {
      const float* cc = colour + ch * n;
      c[ch] = cc[k] + v * (cc[k + 1] - cc[k]);
    }
    return c;
  }
  void stationsDone(const Vec3f& c, float u) {
    attr[Z3Tile::kR] = c.x(), attr[Z3Tile::kG] = c.y(), attr[Z3Tile::kB] = c.z();
    if (sp.smooth) {
      const Vec3f m = sp.n0 + u * sp.dn;
      const float len = m.norm();
      if (len > 0) attr[Z3Tile::kNx] = m.x() / len, attr[Z3Tile::kNy] = m.y() / len, attr[Z3Tile::kNz] = m.z() / len;
    }
  }
};

// Whether the SIMD rows shade the segment's fragments (all but textured ones). A segment's
// stations are textured exactly when the frame is (prepareSegment; the SIMD batches take only
// untextured frames), so the record's SegmentExtra (a cache miss) is not read for it.
bool shadedInRows(const PreparedSegment& sp, const FrameContext& frame) {
  return sp.shade != SegmentShade::Stations || !frame.texture;
}

// The rows' shading of an untextured segment (detail::SegmentShadeRows), written field by field
// into `shade` (a whole struct built on the stack and copied cost store-forwarding stalls per
// segment: issue 13, i13raster2).
void shadeRows(const PreparedSegment& sp, detail::SegmentShadeRows& shade) {
  const bool stations = sp.shade == SegmentShade::Stations;
  shade.attr = sp.attr;
  shade.dc = sp.dc.data(), shade.n0 = sp.n0.data(), shade.dn = sp.dn.data();
  shade.dn2 = sp.dn.squaredNorm();
  shade.smooth = sp.smooth && (sp.shade == SegmentShade::Smooth || stations);
  shade.exactNormal = stations;
  shade.stations = 0, shade.stationColour = nullptr, shade.stationPadded = false;
  if (stations && sp.stationCount >= 2) {  // in the record
    shade.stations = sp.stationCount;
    shade.stationColour = sp.stationColour;
  } else if (stations && sp.stationCount < 0 && sp.extra->stations >= 2) {  // padded (SegmentExtra::colour)
    shade.stationPadded = true;
    shade.stations = sp.extra->stations;
    shade.stationColour = sp.extra->colour.data();
  }
}

// ScreenSpace segments: the closed form evaluated in SIMD over the rows' spans of the cutoff
// region (`given`, else forEachRowSpan's), straight into the Z^3 tile (detail/splat_rows.h).
void rasterizeRows(const PreparedSegment& sp, const SplatContext& ctx, const PixelRect& r,
                   const detail::RowSpan* given = nullptr, int givenCount = 0) {
  auto eachSpan = [&](auto&& emit) {
    if (!given) return forEachRowSpan(sp, r, true, emit);
    for (int i = 0; i < givenCount; ++i) emit(given[i].y, given[i].x0, given[i].x1);
  };
  detail::RowSpan spans[detail::kBlock];
  int spanCount = 0;
  uint64_t inserted = 0;
  if (shadedInRows(sp, ctx.frame)) {  // straight into the Z^3 tile, attributes in SIMD
    detail::SegmentShadeRows shade;
    shadeRows(sp, shade);
    if (given && givenCount <= detail::kBlock) {  // the batch's spans as they are (no copy)
      if (givenCount > 0) inserted = detail::segmentRowsZ3(sp.raster, shade, given, givenCount, ctx.tile);
      ctx.tile.addFragments(inserted);
      return;
    }
    auto flush = [&] {
      inserted += detail::segmentRowsZ3(sp.raster, shade, spans, spanCount, ctx.tile);
      spanCount = 0;
    };
    eachSpan([&](int y, int xb, int xe) {
      if (spanCount == detail::kBlock) flush();
      spans[spanCount++] = {y, xb, xe};
    });
    if (spanCount > 0) flush();
    ctx.tile.addFragments(inserted);
    return;
  }
  // textured: fragments in blocks, attributes per fragment
  FragmentAttributes shade(sp, ctx.frame);
  detail::FragmentBlock fb;
  int pixels = 0;
  auto flush = [&] {
    const int m = detail::segmentFragments(sp.raster, spans, spanCount, fb);
    for (int i = 0; i < m; ++i) {
      shade.at(fb.p[i]);
      ctx.tile.insert(int(fb.x[i]), int(fb.y[i]), fb.depth[i], fb.q[i], fb.weight[i], shade.attr);
    }
    inserted += uint64_t(m);
    spanCount = pixels = 0;
  };
  eachSpan([&](int y, int xb, int xe) {
    for (int x0 = xb; x0 < xe; x0 += detail::kBlock) {
      const int x1 = std::min(xe, x0 + detail::kBlock);
      if (pixels + (x1 - x0) > detail::kBlock) flush();
      spans[spanCount++] = {y, x0, x1};
      pixels += x1 - x0;
    }
  });
  if (spanCount > 0) flush();
  ctx.tile.addFragments(inserted);
}

// Approx and Reference: per pixel, scalar.
void rasterizeScalar(const PreparedSegment& sp, const SplatContext& ctx, const PixelRect& r) {
  const detail::SegmentRaster& k = sp.raster;
  FragmentAttributes shade(sp, ctx.frame);
  const QuadSpans quad(sp);
  uint64_t inserted = 0;
  for (int y = r.y0; y < r.y1; ++y) {
    const float py = float(y) + 0.5f;
    int xb, xe;
    if (!quad.row(r, py, xb, xe)) continue;
    for (int x = xb; x < xe; ++x) {
      const float px = float(x) + 0.5f;
      const float nr = k.N.at(px, py);
      if (!(nr < 0)) continue;  // ray parallel to or leaving the facing plane
      const float t = k.depthNum / nr;
      if (k.clipDepth && (t < k.nearD || t > k.farD)) continue;
      const float inr = 1.0f / nr;
      const float a = k.A.at(px, py) * inr - k.a0, b = k.B.at(px, py) * inr - k.b0;
      const float w = weightAt(sp, a, b);
      if (!(w > 0)) continue;
      const float u = std::clamp(a / k.length, 0.0f, 1.0f);
      shade.at(u);
      ctx.tile.insert(x, y, t, k.zThreshold0 + u * (k.zThreshold1 - k.zThreshold0), w, shade.attr);
      ++inserted;
    }
  }
  ctx.tile.addFragments(inserted);
}

}  // namespace

std::vector<detail::RowSpan> segmentRowSpans(const PreparedSegment& sp, const PixelRect& rect, bool tight) {
  std::vector<detail::RowSpan> out;
  const PixelRect r = sp.bounds.intersect(rect);
  if (!r.empty()) forEachRowSpan(sp, r, tight, [&](int y, int xb, int xe) { out.push_back({y, xb, xe}); });
  return out;
}

void rasterizeSegment(const PreparedSegment& sp, const SplatContext& ctx) {
  const PixelRect r = sp.bounds.intersect(ctx.rect);
  if (r.empty()) return;
  if (sp.method == SegmentMethod::ScreenSpace) return rasterizeRows(sp, ctx, r);
  rasterizeScalar(sp, ctx, r);
}

void rasterizeSegments(const PreparedSegment* const* segs, int n, const SplatContext& ctx) {
  // the rows' spans of the one-piece ScreenSpace segments at once (a band of at most kBlock
  // rows of the tile: taller tiles take the one-by-one path), then every segment in order
  const int stride = ctx.rect.height();
  const detail::SegmentRaster* batch[kRasterBatch];
  PixelRect rects[kRasterBatch];
  int slot[kRasterBatch], counts[kRasterBatch], widest[kRasterBatch], pixels[kRasterBatch];
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const PreparedSegment& sp = *segs[i];
    slot[i] = -1;
    const PixelRect r = sp.bounds.intersect(ctx.rect);
    if (r.empty() || sp.method != SegmentMethod::ScreenSpace || sp.raster.pieceCount != 1 || stride > detail::kBlock)
      continue;
    slot[i] = m;
    batch[m] = &sp.raster;
    rects[m++] = r;
    if (sp.shade == SegmentShade::Stations) {  // its stations, read after the spans
      if (sp.stationCount >= 0) {
        __builtin_prefetch(sp.stationColour);  // (the record's cold line)
      } else {  // the SegmentExtra's fields (its colours when the item is built)
        const char* x = reinterpret_cast<const char*>(sp.extra.get());
        __builtin_prefetch(x + offsetof(SegmentExtra, colour));
        __builtin_prefetch(x + offsetof(SegmentExtra, stations));
      }
    }
  }
  thread_local std::vector<detail::RowSpan> spans;
  if (m > 0) {
    if (spans.size() < size_t(kRasterBatch * stride)) spans.resize(size_t(kRasterBatch * stride));
    detail::segmentSpansBatch(batch, rects, m, kSpanSlack, spans.data(), stride, counts, widest, pixels);
  }
  // runs of consecutive ones shaded in the rows in one call (detail::segmentRowsRunZ3)
  detail::SegmentRowsItem items[kRasterBatch];
  int runLength = 0;
  auto flush = [&] {
    if (runLength > 0) ctx.tile.addFragments(detail::segmentRowsRunZ3(items, runLength, ctx.tile));
    runLength = 0;
  };
  for (int i = 0; i < n; ++i) {
    const int k = slot[i];
    const PreparedSegment& sp = *segs[i];
    if (k >= 0 && counts[k] >= 0 && shadedInRows(sp, ctx.frame)) {
      if (counts[k] > 0) {
        detail::SegmentRowsItem& item = items[runLength++];
        item.raster = &sp.raster;
        shadeRows(sp, item.shade);
        item.spans = spans.data() + size_t(k) * size_t(stride);
        item.count = counts[k];
        item.widest = widest[k], item.pixels = pixels[k];
        if (item.shade.stationPadded) {  // read by the rows
          __builtin_prefetch(item.shade.stationColour);
          __builtin_prefetch(item.shade.stationColour + 3 * item.shade.stations - 1);
        }
      }
      continue;
    }
    flush();
    if (k >= 0 && counts[k] >= 0) rasterizeRows(sp, ctx, rects[k], spans.data() + size_t(k) * size_t(stride), counts[k]);
    else rasterizeSegment(sp, ctx);
  }
  flush();
}

}  // namespace linesurf
