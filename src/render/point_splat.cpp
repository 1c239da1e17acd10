// Object-space EWA point splats, thesis §4.2.2 and §6.2.2 (see point_splat.h).
#include "detail/splat_math.h"
#include "linesurf/render/point_splat.h"

#include <algorithm>
#include <cmath>

namespace linesurf {

namespace {

// Largest stretch of the resampling filter relative to the reconstruction sigma. Near edge-on
// splats the warped prefilter J^-1 V_h J^-T grows without bound (the plane projects to a line);
// past this stretch the splat is cut, which costs nothing visible (its screen width stays below
// a pixel) and keeps the footprint finite.
constexpr float kMaxStretch = 24.0f;
// Splats seen closer to edge-on than this |cos| are dropped as culled (they project to a line).
constexpr float kMinFacing = 2e-3f;


}  // namespace

PrimitiveStatus preparePoint(const Point& point, uint32_t index, const FrameContext& frame, PreparedPoint& out) {
  const Camera& cam = frame.cam();
  const RenderOptions& opt = frame.opt();
  out.index = index;
  out.bounds = {};
  if (!(point.radius > 0) || !std::isfinite(point.radius) || !point.position.allFinite() || !point.normal.allFinite())
    return PrimitiveStatus::Degenerate;

  // model-view transform
  const Vec3f c = cam.toCamera(point.position);
  const float d = -c.z();
  Vec3f n = cam.rotation() * point.normal;
  float nn = n.norm();
  const float cn = c.norm();
  if (!(cn > 0)) return PrimitiveStatus::Outside;
  const Vec3f toEye = -c / cn;
  if (nn > 0) {
    n /= nn;
  } else {
    n = toEye;  // no normal: a disc facing the viewer (raw scans; the CLI computes normals first)
  }
  // back-face culling
  float facing = n.dot(toEye);
  if (facing < 0) {
    if (opt.backfaceCulling) return PrimitiveStatus::Culled;
    n = -n;
    facing = -facing;
  }
  if (facing < kMinFacing) return PrimitiveStatus::Culled;
  // Cheap rejection by the bounding sphere of the largest possible footprint.
  const float sigmaR = opt.reconstructionScale * point.radius;
  const float R = opt.cutoffRadius;
  {
    float reach = R * sigmaR * kMaxStretch;
    if (d + reach < cam.nearDepth() || d - reach > cam.farDepth()) return PrimitiveStatus::Outside;
  }

  // local parameterisation: tangent frame (u, v) of the normal
  Vec3f u = std::abs(n.x()) < 0.9f ? Vec3f(Vec3f::UnitX().cross(n)) : Vec3f(Vec3f::UnitY().cross(n));
  u.normalize();
  Vec3f v = n.cross(u);

  // warping: local Jacobian of (plane coords) -> screen at the centre (perspective projection)
  float r0, r1;
  Vec2f e0;
  if (d > 0) {
    const float f = cam.focalPixels();
    const Vec3f gx(f / d, 0, f * c.x() / (d * d));    // d sx / d p
    const Vec3f gy(0, -f / d, -f * c.y() / (d * d));  // d sy / d p
    Eigen::Matrix2f J;
    J << gx.dot(u), gx.dot(v), gy.dot(u), gy.dot(v);
    // V = sigma_r^2 I + V_h (J^T J)^-1   (object-space EWA resampling filter, §4.2.2)
    Eigen::Matrix2f JtJ = J.transpose() * J;
    float det = JtJ.determinant();
    Eigen::Matrix2f V = Eigen::Matrix2f::Identity() * (sigmaR * sigmaR);
    if (opt.prefilterVariance > 0) {
      if (!(det > 0)) return PrimitiveStatus::Culled;
      Eigen::Matrix2f inv;
      inv << JtJ(1, 1), -JtJ(0, 1), -JtJ(1, 0), JtJ(0, 0);
      V += (opt.prefilterVariance / det) * inv;
    }
    // Rot(theta) Lambda^2 Rot(theta)^T (§5.2.3.1): closed-form symmetric 2x2 eigen-decomposition
    float a = V(0, 0), b = V(0, 1), cc = V(1, 1);
    float mean = 0.5f * (a + cc), diff = 0.5f * (a - cc);
    float rad = std::sqrt(diff * diff + b * b);
    float l0 = mean + rad, l1 = std::max(mean - rad, 1e-30f);
    if (std::abs(b) > 1e-30f * (std::abs(a) + std::abs(cc)) && b != 0) {
      e0 = Vec2f(l0 - cc, b).normalized();
    } else {
      e0 = a >= cc ? Vec2f(1, 0) : Vec2f(0, 1);
    }
    r0 = std::min(std::sqrt(l0), kMaxStretch * sigmaR);
    r1 = std::min(std::sqrt(l1), kMaxStretch * sigmaR);
  } else {
    // centre behind the eye (only its edge can be visible): no prefilter
    e0 = Vec2f(1, 0);
    r0 = r1 = sigmaR;
  }
  const Vec3f E0 = e0.x() * u + e0.y() * v;
  const Vec3f E1 = n.cross(E0);
  if (!(r0 > 0 && r1 > 0) || !E0.allFinite()) return PrimitiveStatus::Degenerate;

  // bounding quadrilateral of the cutoff ellipse (§5.2.3.1) and frustum clipping
  Vec3f quad[4] = {c - R * r0 * E0 - R * r1 * E1, c + R * r0 * E0 - R * r1 * E1, c - R * r0 * E0 + R * r1 * E1,
                   c + R * r0 * E0 + R * r1 * E1};
  // side planes: all corners outside one plane -> outside
  for (const Vec4f& pl : frame.frustum) {
    bool allOut = true;
    for (const Vec3f& q : quad)
      if (pl.head<3>().dot(q) + pl.w() >= 0) { allOut = false; break; }
    if (allOut) return PrimitiveStatus::Outside;
  }
  const Vec3f quadCycle[4] = {quad[0], quad[1], quad[3], quad[2]};
  float x0, y0, x1, y1;
  bool depthClipped = false;
  if (!detail::clippedScreenBounds(cam, quadCycle, 4, x0, y0, x1, y1, depthClipped)) return PrimitiveStatus::Outside;
  // pixel centres (i + 0.5) inside [x0, x1]; clamp first so that the int conversion is defined
  const float lim = 1e7f;
  x0 = std::clamp(x0, -lim, lim), x1 = std::clamp(x1, -lim, lim), y0 = std::clamp(y0, -lim, lim), y1 = std::clamp(y1, -lim, lim);
  PixelRect bb{int(std::floor(x0 - 0.5f)) + 1, int(std::floor(y0 - 0.5f)) + 1, int(std::floor(x1 - 0.5f)) + 1,
               int(std::floor(y1 - 0.5f)) + 1};
  PixelRect view{0, 0, cam.width(), cam.height()};
  out.bounds = bb.intersect(view);
  if (out.bounds.empty()) return PrimitiveStatus::Outside;
  const bool sideClipped = out.bounds.x0 != bb.x0 || out.bounds.y0 != bb.y0 || out.bounds.x1 != bb.x1 ||
                           out.bounds.y1 != bb.y1;

  out.center = c;
  out.normal = n;
  out.axis0 = E0 / r0;
  out.axis1 = E1 / r1;
  out.weightScale = 1.0f / (r0 * r1);  // §5.2.3.3 weight scaling 1/(r0 r1)
  // depth half-extent of the cutoff ellipse, plus the primitive radius (delta-z, §6.2.3.2)
  const float extent = R * std::sqrt(r0 * r0 * E0.z() * E0.z() + r1 * r1 * E1.z() * E1.z()) + point.radius;
  out.zThreshold = frame.zThreshold(extent);
  const Color col = frame.primitiveColor(point.color);
  out.albedo = col.head<3>();
  out.alpha = std::clamp(col.w(), 0.0f, 1.0f);
  out.clipped = depthClipped;
  out.flat = out.bounds.width() <= PreparedPoint::kFlatShadeSpan && out.bounds.height() <= PreparedPoint::kFlatShadeSpan;
  if (!opt.perPixelLighting) {  // Gouraud at the quad's vertices (§6.2.2)
    if (out.flat)
      out.cornerColor[0] = frame.shade(out.albedo, n, c);
    else
      for (int i = 0; i < 4; ++i) out.cornerColor[i] = frame.shade(out.albedo, n, quad[i]);
  }
  return depthClipped || sideClipped ? PrimitiveStatus::Clipped : PrimitiveStatus::Drawn;
}

void rasterizePoint(const PreparedPoint& sp, const SplatContext& ctx) {
  const PixelRect r = sp.bounds.intersect(ctx.rect);
  if (r.empty()) return;
  const Camera& cam = ctx.frame.cam();
  const float f = cam.focalPixels();
  const Vec2f pp = cam.principalPoint();
  const float cutoffQ = ctx.frame.cutoffQ;
  const float R = ctx.frame.opt().cutoffRadius;
  const bool perPixel = ctx.frame.opt().perPixelLighting;
  const float nearD = cam.nearDepth(), farD = cam.farDepth();
  // Along the ray r(x, y) = ((x - cx)/f, -(y - cy)/f, -1) (depth 1) the tangent plane is hit at
  // depth t = (n.c) / N with N = n.r, at plane coordinates s = S / N, t' = T / N where
  // S = (n.c)(a0.r) - (a0.c) N and T likewise: N, S, T are affine in the pixel position. The
  // cutoff ellipse q = (S^2 + T^2) / N^2 <= cutoff^2 is therefore a conic in the pixel plane; each
  // row is clipped to the exact span where S^2 + T^2 - cutoff^2 N^2 <= 0 (a quadratic in x), so
  // only pixels inside the splat are visited (the thesis rasterises the bounding quad and reads
  // the weight texture; this is equivalent and perspective-exact).
  const Vec3f& n = sp.normal;
  const float nc = n.dot(sp.center);
  const float a0c = sp.axis0.dot(sp.center), a1c = sp.axis1.dot(sp.center);
  auto lin = [&](const Vec3f& k, float& dx, float& dy, float& c0) {
    dx = k.x() / f;
    dy = -k.y() / f;
    c0 = -k.x() * pp.x() / f + k.y() * pp.y() / f - k.z();
  };
  float ndx, ndy, nc0, adx, ady, ac0, bdx, bdy, bc0;
  lin(n, ndx, ndy, nc0);
  lin(sp.axis0, adx, ady, ac0);
  lin(sp.axis1, bdx, bdy, bc0);
  const float Sx = nc * adx - a0c * ndx, Sy = nc * ady - a0c * ndy, Sc = nc * ac0 - a0c * nc0;
  const float Tx = nc * bdx - a1c * ndx, Ty = nc * bdy - a1c * ndy, Tc = nc * bc0 - a1c * nc0;
  Fragment fr;
  fr.zThreshold = sp.zThreshold;
  fr.alpha = sp.alpha;
  fr.normal = n;
  // Gouraud: bilinear in the quad's corner colours with u = s/2R + 1/2, v = t'/2R + 1/2; inside
  // the cutoff |s|, |t'| <= R, so it is the polynomial C0 + Cs s + Ct t' + Cst s t' (no clamping).
  const float inv2R = 0.5f / R;
  const Vec3f& k00 = sp.cornerColor[0];
  const Vec3f& k10 = sp.cornerColor[1];
  const Vec3f& k01 = sp.cornerColor[2];
  const Vec3f& k11 = sp.cornerColor[3];
  const Vec3f C0 = 0.25f * (k00 + k10 + k01 + k11);
  const Vec3f Cs = 0.5f * inv2R * (k10 - k00 + k11 - k01);
  const Vec3f Ct = 0.5f * inv2R * (k01 - k00 + k11 - k10);
  const Vec3f Cst = inv2R * inv2R * (k00 - k10 - k01 + k11);
  const detail::GaussTable& gauss = detail::kGaussTable;
  const bool flat = sp.flat && !perPixel;
  if (flat) fr.color = sp.cornerColor[0];
  const float qa = Sx * Sx + Tx * Tx - cutoffQ * ndx * ndx;
  for (int y = r.y0; y < r.y1; ++y) {
    const float py = float(y) + 0.5f;
    const float S0 = Sy * py + Sc, T0 = Ty * py + Tc, N0 = ndy * py + nc0;
    int xb = r.x0, xe = r.x1;
    if (qa > 0) {
      // span of the row inside the conic: qa x^2 + qb x + qc <= 0 (x = pixel centre)
      const float qb = 2 * (Sx * S0 + Tx * T0 - cutoffQ * ndx * N0);
      const float qc = S0 * S0 + T0 * T0 - cutoffQ * N0 * N0;
      const float disc = qb * qb - 4 * qa * qc;
      if (!(disc > 0)) continue;
      const float sq = std::sqrt(disc), inv = 0.5f / qa;
      const float xl = (-qb - sq) * inv, xr = (-qb + sq) * inv;
      // pixel centres x + 0.5 in [xl, xr], widened by a pixel against rounding
      // (fmax/fmin also drop NaN from an overflowing discriminant and keep int() defined)
      xb = std::max(xb, int(std::floor(std::fmax(xl - 0.5f, float(xb) - 1.0f))));
      xe = std::min(xe, int(std::floor(std::fmin(xr - 0.5f, float(xe)))) + 2);
    }
    for (int x = xb; x < xe; ++x) {
      const float px = float(x) + 0.5f;
      const float N = ndx * px + N0;
      if (!(N < 0)) continue;  // ray parallel to or leaving the facing plane
      const float S = Sx * px + S0, T = Tx * px + T0;
      const float iN = 1.0f / N;
      const float s = S * iN, tt = T * iN;
      const float q = s * s + tt * tt;
      if (!(q <= cutoffQ)) continue;
      const float t = nc * iN;
      if (sp.clipped && (t < nearD || t > farD)) continue;
      fr.depth = t;
      fr.weight = gauss(q) * sp.weightScale;
      if (flat) {
      } else if (perPixel) {
        const Vec3f p = t * Vec3f((px - pp.x()) / f, -(py - pp.y()) / f, -1.0f);
        fr.color = ctx.frame.shade(sp.albedo, n, p);
      } else {
        fr.color = C0 + s * Cs + tt * Ct + (s * tt) * Cst;  // bilinear Gouraud over the quad
      }
      ctx.tile.insert(x, y, fr);
    }
  }
}

}  // namespace linesurf
