// Object-space EWA point splats, thesis §4.2.2 and §6.2.2 (see point_splat.h).
#include "point_splat.h"

#include <algorithm>
#include <cmath>
#include <new>

#include "splat_rules.h"

namespace linesurf {

namespace {

using detail::Affine2;
using detail::kMaxStretch;
using detail::kMinFacing;
using detail::pixelBounds;

// The splat in camera space after culling and warping: centre, unit normal facing the viewer,
// plane axes scaled so that q = (axis0.(p - c))^2 + (axis1.(p - c))^2 is the Mahalanobis
// distance in the resampling filter V, weight scale 1/sqrt(det V), depth half-extent of the
// cutoff ellipse.
struct Warped {
  Vec3f c, n, axis0, axis1;
  Vec3f B0, B1;  ///< plane vectors of unit plane coordinates: p = c + s B0 + t B1
  float weightScale = 0, depthExtent = 0;
};

// ray/plane constants of a warped splat (point_splat.h, detail::PointRaster)
void planeRaster(const Camera& cam, const Warped& s, detail::PointRaster& r) {
  const Affine2 N = detail::rayDot(cam, s.n), A0 = detail::rayDot(cam, s.axis0), A1 = detail::rayDot(cam, s.axis1);
  const float nc = s.n.dot(s.c), a0c = s.axis0.dot(s.c), a1c = s.axis1.dot(s.c);
  // s = (a0.(t r - c)) with t = nc / N:  s = (nc A0 - a0c N) / N
  auto comb = [](float k, const Affine2& f, float l, const Affine2& g) {
    return Affine2{k * f.dx - l * g.dx, k * f.dy - l * g.dy, k * f.c - l * g.c};
  };
  r.N = N;
  r.S = comb(nc, A0, a0c, N);
  r.T = comb(nc, A1, a1c, N);
  r.depthNum = nc;
  r.weightScale = s.weightScale;
}

// Screen bounding box of the projected cutoff ellipse (detail::conicBounds).
bool conicBounds(const detail::PointRaster& r, double c, double& x0, double& y0, double& x1, double& y1) {
  return detail::conicBounds(r.S, r.T, r.N, c, x0, y0, x1, y1);
}

// Closed-form warp (common case): V^-1 = L L^T. False when the exact path must run instead
// (stretched past kMaxStretch, centre behind the eye, cutoff ellipse crossing near or far).
bool warpClosedForm(const Camera& cam, const RenderOptions& opt, float sigmaR, const Vec3f& u, const Vec3f& v,
                    Warped& s, bool& degenerate) {
  const float d = -s.c.z();
  if (!(d > 0)) return false;
  const float s2 = sigmaR * sigmaR;
  float a = s2, b = 0, cc = s2;
  if (opt.prefilterVariance > 0) {
    const float f = cam.focalPixels();
    const Vec3f gx(f / d, 0, f * s.c.x() / (d * d)), gy(0, -f / d, -f * s.c.y() / (d * d));
    const float j00 = gx.dot(u), j01 = gx.dot(v), j10 = gy.dot(u), j11 = gy.dot(v);
    // V = sigma_r^2 I + V_h (J^T J)^-1 (object-space EWA resampling filter, §4.2.2)
    const float p = j00 * j00 + j10 * j10, q = j00 * j01 + j10 * j11, r = j01 * j01 + j11 * j11;
    const float det = p * r - q * q;
    if (!(det > 0)) {
      degenerate = true;  // edge-on: culled as before
      return false;
    }
    const float k = opt.prefilterVariance / det;
    a += k * r, b -= k * q, cc += k * p;
  }
  const float mean = 0.5f * (a + cc), diff = 0.5f * (a - cc);
  const float maxStretch2 = (kMaxStretch * sigmaR) * (kMaxStretch * sigmaR);
  if (!(mean + std::sqrt(diff * diff + b * b) <= maxStretch2)) return false;
  const float detV = a * cc - b * b;
  if (!(detV > 0)) return false;
  // V^-1 = [cc -b; -b a] / detV = L L^T
  const float l00 = std::sqrt(cc / detV), l10 = -b / detV / l00, l11 = std::sqrt(std::max(a / detV - l10 * l10, 0.0f));
  if (!(l11 > 0)) return false;
  s.axis0 = l00 * u + l10 * v;
  s.axis1 = l11 * v;
  s.B0 = u / l00;
  s.B1 = (v - (l10 / l00) * u) / l11;
  s.weightScale = 1.0f / std::sqrt(detV);  // §5.2.3.3 weight scaling 1/(r0 r1)
  const float gu = u.z(), gv = v.z();
  s.depthExtent = opt.cutoffRadius * std::sqrt(std::max(0.0f, a * gu * gu + 2 * b * gu * gv + cc * gv * gv));
  return d - s.depthExtent >= cam.nearDepth() && d + s.depthExtent <= cam.farDepth();
}

// The thesis's construction (exact path): eigen-decomposition of V with the stretch clamp, the
// bounding quadrilateral of the cutoff ellipse, clipped against the frustum.
PrimitiveStatus warpExact(const FrameContext& frame, float sigmaR, const Vec3f& u, const Vec3f& v, Warped& s,
                          PixelRect& bounds, bool& clipped) {
  const Camera& cam = frame.cam();
  const RenderOptions& opt = frame.opt();
  const float R = opt.cutoffRadius, d = -s.c.z();
  float r0, r1;
  Vec2f e0;
  if (d > 0) {
    const float f = cam.focalPixels();
    const Vec3f gx(f / d, 0, f * s.c.x() / (d * d)), gy(0, -f / d, -f * s.c.y() / (d * d));
    Eigen::Matrix2f J;
    J << gx.dot(u), gx.dot(v), gy.dot(u), gy.dot(v);
    const Eigen::Matrix2f JtJ = J.transpose() * J;
    const float det = JtJ.determinant();
    Eigen::Matrix2f V = Eigen::Matrix2f::Identity() * (sigmaR * sigmaR);
    if (opt.prefilterVariance > 0) {
      if (!(det > 0)) return PrimitiveStatus::Culled;
      Eigen::Matrix2f inv;
      inv << JtJ(1, 1), -JtJ(0, 1), -JtJ(1, 0), JtJ(0, 0);
      V += (opt.prefilterVariance / det) * inv;
    }
    // Rot(theta) Lambda^2 Rot(theta)^T (§5.2.3.1): closed-form symmetric 2x2 eigen-decomposition
    const float a = V(0, 0), b = V(0, 1), cc = V(1, 1);
    const float mean = 0.5f * (a + cc), diff = 0.5f * (a - cc);
    const float rad = std::sqrt(diff * diff + b * b);
    const float l0 = mean + rad, l1 = std::max(mean - rad, 1e-30f);
    e0 = std::abs(b) > 1e-30f * (std::abs(a) + std::abs(cc)) && b != 0 ? Vec2f(Vec2f(l0 - cc, b).normalized())
                                                                       : (a >= cc ? Vec2f(1, 0) : Vec2f(0, 1));
    r0 = std::min(std::sqrt(l0), kMaxStretch * sigmaR);
    r1 = std::min(std::sqrt(l1), kMaxStretch * sigmaR);
  } else {  // centre behind the eye (only its edge can be visible): no prefilter
    e0 = Vec2f(1, 0);
    r0 = r1 = sigmaR;
  }
  const Vec3f E0 = e0.x() * u + e0.y() * v, E1 = s.n.cross(E0);
  if (!(r0 > 0 && r1 > 0) || !E0.allFinite()) return PrimitiveStatus::Degenerate;
  s.axis0 = E0 / r0;
  s.axis1 = E1 / r1;
  s.B0 = r0 * E0;
  s.B1 = r1 * E1;
  s.weightScale = 1.0f / (r0 * r1);
  s.depthExtent = R * std::sqrt(r0 * r0 * E0.z() * E0.z() + r1 * r1 * E1.z() * E1.z());
  const Vec3f quad[4] = {s.c - R * r0 * E0 - R * r1 * E1, s.c + R * r0 * E0 - R * r1 * E1,
                         s.c + R * r0 * E0 + R * r1 * E1, s.c - R * r0 * E0 + R * r1 * E1};
  for (const Vec4f& pl : frame.frustum) {  // all corners outside one side plane: outside
    bool allOut = true;
    for (const Vec3f& q : quad)
      if (pl.head<3>().dot(q) + pl.w() >= 0) { allOut = false; break; }
    if (allOut) return PrimitiveStatus::Outside;
  }
  float x0, y0, x1, y1;
  bool depthClipped = false, cut = false;
  if (!detail::clippedScreenBounds(cam, quad, 4, x0, y0, x1, y1, depthClipped)) return PrimitiveStatus::Outside;
  bounds = pixelBounds(cam, x0, y0, x1, y1, cut);
  if (bounds.empty()) return PrimitiveStatus::Outside;
  clipped = depthClipped;
  return depthClipped || cut ? PrimitiveStatus::Clipped : PrimitiveStatus::Drawn;
}

// Gouraud lighting (§6.2.2) at the corners (s, t) = (+-R, +-R) of the bounding quadrilateral,
// as the bilinear polynomial C0 + Cs s + Ct t + Cst s t; small splats are lit once. `ln`: the
// shading normal (camera space, unit, on the viewer's side of the plane): s.n or the point's own.
void light(const FrameContext& frame, const Warped& s, const Vec3f& ln, const PixelRect& bounds, PreparedPoint& out,
           PointGouraud* g) {
  const Vec3f albedo(out.color[0], out.color[1], out.color[2]);
  if (!PreparedPoint::gouraud(bounds, false)) {
    const Vec3f c = frame.shade(albedo, ln, s.c);
    out.color[0] = c.x(), out.color[1] = c.y(), out.color[2] = c.z();
    return;
  }
  const float R = frame.opt().cutoffRadius;
  const Vec3f k00 = frame.shade(albedo, ln, s.c - R * s.B0 - R * s.B1), k10 = frame.shade(albedo, ln, s.c + R * s.B0 - R * s.B1),
              k01 = frame.shade(albedo, ln, s.c - R * s.B0 + R * s.B1), k11 = frame.shade(albedo, ln, s.c + R * s.B0 + R * s.B1);
  // bilinear in u = s/2R + 1/2, v = t/2R + 1/2; inside the cutoff |s|, |t| <= R (no clamping)
  const float inv2R = 0.5f / R;
  g->C0 = 0.25f * (k00 + k10 + k01 + k11);
  g->Cs = 0.5f * inv2R * (k10 - k00 + k11 - k01);
  g->Ct = 0.5f * inv2R * (k01 - k00 + k11 - k10);
  g->Cst = inv2R * inv2R * (k00 - k10 - k01 + k11);
}

}  // namespace

PrimitiveStatus preparePoint(const Point& point, uint32_t index, const FrameContext& frame, const PointSlots& slot) {
  const Camera& cam = frame.cam();
  const RenderOptions& opt = frame.opt();
  PreparedPoint& out = *new (slot.hot) PreparedPoint;
  PixelRect& bounds = *new (slot.bounds) PixelRect{};
  PointCold& cold = *new (slot.cold) PointCold;
  cold.index = index;
  detail::PointRaster raster;
  if (!(point.radius > 0) || !std::isfinite(point.radius) || !point.position.allFinite() || !point.normal.allFinite())
    return PrimitiveStatus::Degenerate;

  // model-view transform and back-face culling, before anything else
  Warped s;
  s.c = cam.toCamera(point.position);
  Vec3f n = cam.rotation() * point.normal;
  const float nn2 = n.squaredNorm(), nDotEye = -n.dot(s.c);
  if (opt.backfaceCulling && nn2 > 0 && nDotEye < 0) return PrimitiveStatus::Culled;
  const float cn = s.c.norm();
  if (!(cn > 0)) return PrimitiveStatus::Outside;
  // no normal: a disc facing the viewer (raw scans; the CLI computes normals first)
  float facing = 1;
  bool flipped = false;
  if (nn2 > 0) {
    const float inv = 1.0f / std::sqrt(nn2);
    n *= inv;
    facing = nDotEye * inv / cn;
    if (facing < 0) {  // two-sided: lit from the viewer's side
      n = -n;
      facing = -facing;
      flipped = true;
    }
  } else {
    n = -s.c / cn;
  }
  if (facing < kMinFacing) return PrimitiveStatus::Culled;
  s.n = n;
  // cheap rejection by depth with the largest possible footprint
  const float sigmaR = opt.reconstructionScale * point.radius;
  const float d = -s.c.z(), reach = opt.cutoffRadius * sigmaR * kMaxStretch;
  if (d + reach < cam.nearDepth() || d - reach > cam.farDepth()) return PrimitiveStatus::Outside;

  // local parameterisation: tangent frame (u, v) of the normal
  Vec3f u = std::abs(n.x()) < 0.9f ? Vec3f(Vec3f::UnitX().cross(n)) : Vec3f(Vec3f::UnitY().cross(n));
  u.normalize();
  const Vec3f v = n.cross(u);

  // warping and screen bounds: closed form, or the exact path
  PrimitiveStatus status = PrimitiveStatus::Drawn;
  bool clipped = false, degenerate = false, exact = true;
  if (warpClosedForm(cam, opt, sigmaR, u, v, s, degenerate)) {
    planeRaster(cam, s, raster);
    double x0, y0, x1, y1;
    bool cut = false;
    if (conicBounds(raster, double(frame.cutoffQ), x0, y0, x1, y1)) {
      exact = false;
      bounds = pixelBounds(cam, x0, y0, x1, y1, cut);
      if (bounds.empty()) return PrimitiveStatus::Outside;
      if (cut) status = PrimitiveStatus::Clipped;
    }
  } else if (degenerate) {
    return PrimitiveStatus::Culled;
  }
  if (exact) {
    status = warpExact(frame, sigmaR, u, v, s, bounds, clipped);
    if (status != PrimitiveStatus::Drawn && status != PrimitiveStatus::Clipped) {
      bounds = {};
      return status;
    }
    planeRaster(cam, s, raster);
  }
  out.N = raster.N, out.S = raster.S, out.T = raster.T;
  out.depthNum = raster.depthNum;
  out.setWeightScale(frame.pointMasses ? raster.weightScale * frame.pointMasses[index] : raster.weightScale, clipped);
  // depth half-extent of the cutoff ellipse plus the primitive radius (delta-z, §6.2.3.2)
  out.zThreshold = frame.zThreshold(s.depthExtent + point.radius);
  const Color col = frame.primitiveColor(point.color);
  out.color[0] = col.x(), out.color[1] = col.y(), out.color[2] = col.z(), out.color[3] = std::clamp(col.w(), 0.0f, 1.0f);
  // shading normal (see docs/decisions.md, "Smooth contour models"): the point's own when the model has them, flipped with the plane
  Vec3f ln = n;
  if (frame.pointShadingNormals) {
    Vec3f m = cam.rotation() * frame.pointShadingNormals[index];
    const float ml = m.norm();
    if (ml > 0 && std::isfinite(ml)) {
      m /= ml;
      ln = (nn2 > 0 ? flipped : m.dot(s.c) > 0) ? Vec3f(-m) : m;
    }
  }
  cold.normal[0] = ln.x(), cold.normal[1] = ln.y(), cold.normal[2] = ln.z();
  const float rd = detail::kTailDisc * opt.cutoffRadius * sigmaR, rs2 = rd * rd;  // the disc's tail form
  cold.disc[0] = s.B0.squaredNorm() / rs2, cold.disc[1] = 2 * s.B0.dot(s.B1) / rs2, cold.disc[2] = s.B1.squaredNorm() / rs2;
  if (!opt.perPixelLighting)
    light(frame, s, ln, bounds, out, PreparedPoint::gouraud(bounds, false) ? new (slot.gouraud) PointGouraud : nullptr);
  return status;
}

detail::PointRaster pointRaster(const PreparedPoint& sp, const FrameContext& frame) {
  detail::PointRaster p;
  p.N = sp.N, p.S = sp.S, p.T = sp.T;
  p.depthNum = sp.depthNum;
  p.weightScale = sp.weightScale();
  p.clipDepth = sp.clipDepth();
  p.cutoffQ = frame.cutoffQ;
  p.nearD = frame.cam().nearDepth();
  p.farD = frame.cam().farDepth();
  return p;
}

void rasterizePoints(const PointSlots& slots, const uint32_t* refs, int n, const SplatContext& ctx) {
  static_assert(sizeof(PointGouraud) == 12 * sizeof(float) && sizeof(PointCold) == 8 * sizeof(float));
  const detail::PointRowsFrame F{ctx.frame.cutoffQ, ctx.frame.cam().nearDepth(), ctx.frame.cam().farDepth()};
  detail::PointRunSlots s;
  s.hot = slots.hot, s.bounds = slots.bounds;
  s.normals = slots.cold->normal, s.normalStride = 8;
  if (ctx.tile.tailLayers()) s.disc = slots.cold->disc, s.discStride = 8;
  s.gouraud = ctx.frame.opt().perPixelLighting ? nullptr : slots.gouraud->C0.data(), s.gouraudStride = 12;
  ctx.tile.addFragments(detail::pointRunZ3(F, s, refs, n, ctx.tile));
}

}  // namespace linesurf
