// Supersampled, z-buffered triangle rasterisation: the ground truth of a mesh (mesh_render.h).
// Per frame: vertices to camera space; per face (in parallel) back-face culling, frustum
// rejection, clipping against the near plane and projection to at most two screen triangles;
// binning to screen tiles in face order; per tile (in parallel) edge-function coverage of the
// sample grid with the exact per-sample depth of the face's plane; resolve per pixel, shading
// each visible face once at the centroid of its samples.
#include "linesurf/render/mesh_render.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/core/mesh_normals.h"
#include "splat_context.h"

namespace linesurf {

MeshRenderStats& MeshRenderStats::operator+=(const MeshRenderStats& o) {
  trianglesDrawn += o.trianglesDrawn, trianglesClipped += o.trianglesClipped, trianglesCulled += o.trianglesCulled;
  trianglesOutside += o.trianglesOutside, trianglesDegenerate += o.trianglesDegenerate;
  samplesCovered += o.samplesCovered;
  prepareSeconds += o.prepareSeconds, rasterSeconds += o.rasterSeconds, totalSeconds += o.totalSeconds;
  return *this;
}

BoundingSphere boundingSphere(const TriangleMesh& mesh) {
  Bounds3f b;
  for (const Vec3f& p : mesh.positions)
    if (p.allFinite()) b.extend(p);
  BoundingSphere s;
  if (b.empty()) return s;
  s.center = b.center();
  float r2 = 0;
  for (const Vec3f& p : mesh.positions)
    if (p.allFinite()) r2 = std::max(r2, (p - s.center).squaredNorm());
  s.radius = std::sqrt(r2);
  if (!(s.radius > 0)) s.radius = 1.0f;
  return s;
}

MeshRenderer::MeshRenderer(const TriangleMesh& mesh, const RenderOptions& options, const MeshRenderOptions& mo)
    : mesh_(mesh), options_(options), meshOptions_(mo), sphere_(boundingSphere(mesh)) {
  validate(options_);
  if (mo.supersampling < 1 || mo.supersampling > 16)
    throwBadOption("supersampling", "must be in [1, 16] samples per pixel side");
  normals_ = meshVertexNormals(mesh);  // also checks the face indices
}

MeshRenderResult renderMesh(const TriangleMesh& mesh, const Camera& camera, const RenderOptions& options,
                            const MeshRenderOptions& meshOptions) {
  return MeshRenderer(mesh, options, meshOptions).render(camera);
}

namespace {

enum class FaceStatus : uint8_t { Drawn, Clipped, Culled, Outside, Degenerate };

/// A face after prepare: its camera-space plane n.p = c (n unit, oriented towards the viewer
/// side of the winding), facing flag and up to two screen triangles (near-plane clipped).
struct PreparedFace {
  Vec3f n = Vec3f::Zero();
  float c = 0;
  bool front = true;  ///< the winding faces the camera
  int tris = 0;
  std::array<std::array<Vec2f, 3>, 2> screen;
  PixelRect bounds;
};

struct Sample {
  float invDepth = 0;  ///< 1 / depth of the nearest face; 0 = empty
  uint32_t face = 0;
};

/// Prepares face `tri` (camera-space vertices pc): its plane, facing, culling, frustum test,
/// near-plane clipping and screen triangles within the W x H view.
FaceStatus prepareFace(const std::array<uint32_t, 3>& tri, const std::vector<Vec3f>& pc, const Camera& cam,
                       const RenderOptions& opt, const std::array<Vec4f, 6>& planes, PreparedFace& pf) {
  const float nearD = cam.nearDepth();
  const int W = cam.width(), H = cam.height();
  const Vec3f a = pc[tri[0]], b = pc[tri[1]], c = pc[tri[2]];
  const Vec3f cr = (b - a).cross(c - a);
  const float len = cr.norm();
  if (!a.allFinite() || !b.allFinite() || !c.allFinite() || !(len > 0) || !std::isfinite(len))
    return FaceStatus::Degenerate;
  pf.n = cr / len;
  pf.c = pf.n.dot(a);
  pf.front = pf.c < 0;  // the camera (origin) is on the side the winding normal points to
  if (opt.backfaceCulling && !pf.front) return FaceStatus::Culled;
  if (std::abs(pf.c) <= 1e-12f * (a.norm() + 1e-30f)) return FaceStatus::Degenerate;  // edge-on: covers no sample
  for (const Vec4f& pl : planes) {
    auto out = [&](const Vec3f& p) { return pl.head<3>().dot(p) + pl.w() < 0; };
    if (out(a) && out(b) && out(c)) return FaceStatus::Outside;
  }
  // clip against the near plane depth >= near (Sutherland-Hodgman, one plane)
  std::array<Vec3f, 4> poly;
  int m = 0;
  const Vec3f in[3] = {a, b, c};
  bool clipped = false;
  for (int k = 0; k < 3; ++k) {
    const Vec3f& p = in[k];
    const Vec3f& q = in[(k + 1) % 3];
    const float dp = -p.z() - nearD, dq = -q.z() - nearD;
    if (dp >= 0) poly[size_t(m++)] = p;
    else clipped = true;
    if ((dp >= 0) != (dq >= 0)) poly[size_t(m++)] = p + (q - p) * (dp / (dp - dq));
  }
  if (m < 3) return FaceStatus::Outside;
  std::array<Vec2f, 4> s;
  float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (int k = 0; k < m; ++k) {
    const Vec3f pr = cam.project(poly[size_t(k)]);
    s[size_t(k)] = pr.head<2>();
    x0 = std::min(x0, pr.x()); x1 = std::max(x1, pr.x());
    y0 = std::min(y0, pr.y()); y1 = std::max(y1, pr.y());
  }
  pf.tris = m - 2;
  for (int k = 0; k < pf.tris; ++k) pf.screen[size_t(k)] = {s[0], s[size_t(k) + 1], s[size_t(k) + 2]};
  auto clampi = [](float v, int lo, int hi) { return int(std::clamp(v, float(lo), float(hi))); };
  pf.bounds = PixelRect{clampi(std::floor(x0), 0, W), clampi(std::floor(y0), 0, H), clampi(std::floor(x1) + 1, 0, W),
                        clampi(std::floor(y1) + 1, 0, H)};
  return pf.bounds.empty() ? FaceStatus::Outside : clipped ? FaceStatus::Clipped : FaceStatus::Drawn;
}

/// One frame of the mesh renderer as its tiles see it: the prepared faces, the camera-space
/// vertices and normals, and where the pixels go.
struct MeshFrame {
  const TriangleMesh& mesh;
  const MeshRenderOptions& meshOptions;
  const FrameContext& frame;
  const std::vector<PreparedFace>& faces;
  const std::vector<Vec3f>& pc;  ///< camera-space vertices
  const std::vector<Vec3f>& nc;  ///< camera-space vertex normals
  bool hasColors, textured;
  MeshRenderResult& res;

  /// The tile's samples (S x S per pixel of rect) covered by face fi, nearest first.
  void rasterizeFace(uint32_t fi, const PixelRect& rect, std::vector<Sample>& samples) const {
    const Camera& cam = frame.cam();
    const int S = meshOptions.supersampling;
    const int sw = rect.width() * S, sh = rect.height() * S;
    const float invS = 1.0f / float(S);
    const float invNear = 1.0f / cam.nearDepth(), invFar = 1.0f / cam.farDepth();
    const float f = cam.focalPixels();
    const Vec2f pp = cam.principalPoint();
    const PreparedFace& pf = faces[fi];
    // 1/depth of the face's plane along the ray through (sx, sy): (n . r) / c, affine in sx, sy
    const double ia = double(pf.n.x()) / (double(f) * pf.c), ib = -double(pf.n.y()) / (double(f) * pf.c);
    const double ic = (-double(pf.n.x()) * pp.x() / f + double(pf.n.y()) * pp.y() / f - pf.n.z()) / pf.c;
    for (int k = 0; k < pf.tris; ++k) {
      const auto& v = pf.screen[size_t(k)];
      double area = (double(v[1].x()) - v[0].x()) * (double(v[2].y()) - v[0].y()) -
                    (double(v[1].y()) - v[0].y()) * (double(v[2].x()) - v[0].x());
      if (!(area != 0) || !std::isfinite(area)) continue;
      const double sg = area > 0 ? 1.0 : -1.0;
      // edge functions E_k(x, y) = A_k x + B_k y + C_k >= 0 inside (inclusive: shared edges
      // are covered by both faces, the z test keeps one: no cracks)
      double A[3], B[3], C[3];
      for (int e = 0; e < 3; ++e) {
        const Vec2f& p = v[size_t(e)];
        const Vec2f& q = v[size_t((e + 1) % 3)];
        A[e] = sg * -(double(q.y()) - p.y());
        B[e] = sg * (double(q.x()) - p.x());
        C[e] = -(A[e] * p.x() + B[e] * p.y());
      }
      float bx0 = std::min({v[0].x(), v[1].x(), v[2].x()}), bx1 = std::max({v[0].x(), v[1].x(), v[2].x()});
      float by0 = std::min({v[0].y(), v[1].y(), v[2].y()}), by1 = std::max({v[0].y(), v[1].y(), v[2].y()});
      // sample (i, j) of the tile grid is at rect.x0 + (i + 0.5) / S
      const int i0 = std::max(0, int(std::ceil((bx0 - float(rect.x0)) * float(S) - 0.5f)));
      const int i1 = std::min(sw - 1, int(std::floor((bx1 - float(rect.x0)) * float(S) - 0.5f)));
      const int j0 = std::max(0, int(std::ceil((by0 - float(rect.y0)) * float(S) - 0.5f)));
      const int j1 = std::min(sh - 1, int(std::floor((by1 - float(rect.y0)) * float(S) - 0.5f)));
      for (int j = j0; j <= j1; ++j) {
        const double sy = rect.y0 + (j + 0.5) * invS;
        for (int i = i0; i <= i1; ++i) {
          const double sx = rect.x0 + (i + 0.5) * invS;
          if (A[0] * sx + B[0] * sy + C[0] < 0 || A[1] * sx + B[1] * sy + C[1] < 0 ||
              A[2] * sx + B[2] * sy + C[2] < 0)
            continue;
          const float id = float(ia * sx + ib * sy + ic);
          if (!(id >= invFar && id <= invNear)) continue;
          Sample& smp = samples[size_t(j) * size_t(sw) + size_t(i)];
          if (id > smp.invDepth) smp = {id, fi};
        }
      }
    }
  }

  /// The faces seen at one pixel: their samples, centroid (sums) and nearest 1 / depth.
  struct Hit {
    uint32_t face;
    int count;
    float sx, sy, invDepthMax;
  };

  /// Resolves pixel (x, y) from its hits: each visible face shaded once at the centroid of its
  /// samples, weighted by its share of them; returns the samples covered.
  uint64_t resolvePixel(int x, int y, const std::vector<Hit>& hits) const {
    const Camera& cam = frame.cam();
    const int S = meshOptions.supersampling;
    const Color& bg = frame.opt().background;
    uint64_t cov = 0;
    Vec3f premult = Vec3f::Zero();
    float alphaSum = 0, nearestInv = 0;
    Vec3f nsum = Vec3f::Zero();
    for (const Hit& h : hits) {
      cov += uint64_t(h.count);
      const PreparedFace& pf = faces[h.face];
      const auto& tri = mesh.faces[h.face];
      const float cx = h.sx / float(h.count), cy = h.sy / float(h.count);
      const Vec3f r = cam.rayThrough(cx, cy);
      const float denom = pf.n.dot(r);
      const Vec3f p = denom != 0 ? Vec3f(r * (pf.c / denom)) : Vec3f(pc[tri[0]]);
      // barycentrics of p in the camera-space triangle
      const Vec3f a = pc[tri[0]], b = pc[tri[1]], c = pc[tri[2]];
      const Vec3f nn = (b - a).cross(c - a);
      const float inv = 1.0f / nn.squaredNorm();
      float w0 = nn.dot((c - b).cross(p - b)) * inv, w1 = nn.dot((a - c).cross(p - c)) * inv;
      w0 = std::clamp(w0, 0.0f, 1.0f);
      w1 = std::clamp(w1, 0.0f, 1.0f - w0);
      const float w2 = 1.0f - w0 - w1;
      Vec3f facing = pf.front ? pf.n : Vec3f(-pf.n);  // geometric normal towards the camera
      Vec3f n = facing;
      if (meshOptions.smoothShading) {
        Vec3f ni = w0 * nc[tri[0]] + w1 * nc[tri[1]] + w2 * nc[tri[2]];
        const float l = ni.norm();
        if (l > 0 && std::isfinite(l)) {
          ni /= l;
          if (!pf.front) ni = -ni;  // two-sided lighting of a back face (culling off)
          n = ni;
        }
      }
      Color albedo(1, 1, 1, 1);
      if (textured) {
        const auto& uv = mesh.cornerUVs[h.face];
        const Vec2f u = w0 * uv[0] + w1 * uv[1] + w2 * uv[2];
        albedo = mesh.texture->sampleBilinear(u.x(), u.y());
      } else if (hasColors) {
        albedo = w0 * mesh.colors[tri[0]] + w1 * mesh.colors[tri[1]] + w2 * mesh.colors[tri[2]];
      }
      const Color pcol = frame.primitiveColor(albedo);
      const Vec3f shaded = frame.shade(pcol.head<3>(), n, p);
      const float wgt = pcol.w() * float(h.count) / float(S * S);
      premult += wgt * shaded;
      alphaSum += wgt;
      nearestInv = std::max(nearestInv, h.invDepthMax);
      nsum += float(h.count) * n;
    }
    const float a = std::min(1.0f, alphaSum);
    res.color.at(x, y) = overBackground(Color(premult.x(), premult.y(), premult.z(), a), bg);
    if (res.depth) {
      const float d = 1.0f / nearestInv;
      res.depth->at(x, y) = Color(d, d, d, 1);
    }
    if (res.alpha) res.alpha->at(x, y) = Color(a, a, a, a);
    if (res.normal) {
      const Vec3f n = nsum.norm() > 0 ? Vec3f(nsum.normalized()) : Vec3f::Zero();
      res.normal->at(x, y) = Color(0.5f * (n.x() + 1), 0.5f * (n.y() + 1), 0.5f * (n.z() + 1), 1);
    }
    return cov;
  }

  /// One tile: its faces (bins, in face order) rasterised into its sample grid, then resolved.
  /// Returns the samples covered.
  uint64_t renderTile(const PixelRect& rect, const std::vector<uint32_t>& bin) const {
    const int S = meshOptions.supersampling;
    const float invS = 1.0f / float(S);
    const int sw = rect.width() * S, sh = rect.height() * S;
    std::vector<Sample> samples(size_t(sw) * size_t(sh));
    for (uint32_t fi : bin) rasterizeFace(fi, rect, samples);
    std::vector<Hit> hits;
    hits.reserve(size_t(S * S));
    uint64_t cov = 0;
    for (int y = rect.y0; y < rect.y1; ++y)
      for (int x = rect.x0; x < rect.x1; ++x) {
        hits.clear();
        for (int j = 0; j < S; ++j)
          for (int i = 0; i < S; ++i) {
            const int si = (x - rect.x0) * S + i, sj = (y - rect.y0) * S + j;
            const Sample& smp = samples[size_t(sj) * size_t(sw) + size_t(si)];
            if (smp.invDepth <= 0) continue;
            const float sx = float(x) + (float(i) + 0.5f) * invS, sy = float(y) + (float(j) + 0.5f) * invS;
            auto it = std::find_if(hits.begin(), hits.end(), [&](const Hit& h) { return h.face == smp.face; });
            if (it == hits.end()) hits.push_back({smp.face, 1, sx, sy, smp.invDepth});
            else { ++it->count; it->sx += sx; it->sy += sy; it->invDepthMax = std::max(it->invDepthMax, smp.invDepth); }
          }
        if (!hits.empty()) cov += resolvePixel(x, y, hits);
      }
    return cov;
  }
};

}  // namespace

MeshRenderResult MeshRenderer::render(const Camera& cam) const {
  Timer total;
  MeshRenderResult res;
  MeshRenderStats& st = res.stats;
  const RenderOptions& opt = options_;
  const bool hasColors = !mesh_.colors.empty() && mesh_.colors.size() == mesh_.positions.size();
  const bool textured = mesh_.texture && !mesh_.texture->empty() && mesh_.cornerUVs.size() == mesh_.faces.size();
  const FrameContext frame = FrameContext::make(cam, opt, sphere_, hasColors || textured, nullptr);

  // 1. vertices to camera space
  Timer t;
  const size_t nv = mesh_.positions.size(), nf = mesh_.faces.size();
  std::vector<Vec3f> pc(nv), nc(nv);
  parallelFor(0, nv, [&](size_t i) {
    pc[i] = cam.toCamera(mesh_.positions[i]);
    nc[i] = cam.rotation() * normals_[i];
  }, 4096);

  // 2. prepare faces
  std::vector<PreparedFace> faces(nf);
  std::vector<FaceStatus> status(nf);
  const auto planes = cam.frustumPlanes();
  const int W = cam.width(), H = cam.height();
  parallelFor(0, nf, [&](size_t fi) { status[fi] = prepareFace(mesh_.faces[fi], pc, cam, opt, planes, faces[fi]); }, 1024);
  for (size_t i = 0; i < nf; ++i) switch (status[i]) {
      case FaceStatus::Drawn: ++st.trianglesDrawn; break;
      case FaceStatus::Clipped: ++st.trianglesDrawn; ++st.trianglesClipped; break;
      case FaceStatus::Culled: ++st.trianglesCulled; break;
      case FaceStatus::Outside: ++st.trianglesOutside; break;
      case FaceStatus::Degenerate: ++st.trianglesDegenerate; break;
    }

  // 3. binning, face order within each tile
  const int T = opt.tileSize;
  const int tilesX = (W + T - 1) / T, tilesY = (H + T - 1) / T;
  std::vector<std::vector<uint32_t>> bins(size_t(tilesX) * size_t(tilesY));
  for (size_t i = 0; i < nf; ++i) {
    if (status[i] != FaceStatus::Drawn && status[i] != FaceStatus::Clipped) continue;
    const PixelRect& b = faces[i].bounds;
    for (int ty = b.y0 / T; ty <= (b.y1 - 1) / T; ++ty)
      for (int tx = b.x0 / T; tx <= (b.x1 - 1) / T; ++tx) bins[size_t(ty) * size_t(tilesX) + size_t(tx)].push_back(uint32_t(i));
  }
  st.prepareSeconds = t.seconds();

  // 4. per tile: rasterise the sample grid, then resolve
  t.reset();
  res.color = Image(W, H, opt.background);
  if (opt.depthBuffer) res.depth = Image(W, H, Color(0, 0, 0, 0));
  if (opt.alphaBuffer) res.alpha = Image(W, H, Color(0, 0, 0, 0));
  if (opt.normalBuffer) res.normal = Image(W, H, Color(0, 0, 0, 0));
  const MeshFrame mf{mesh_, meshOptions_, frame, faces, pc, nc, hasColors, textured, res};
  std::vector<uint64_t> covered(bins.size(), 0);
  parallelFor(0, bins.size(), [&](size_t tile) {
    const int tx = int(tile % size_t(tilesX)), ty = int(tile / size_t(tilesX));
    const PixelRect rect{tx * T, ty * T, std::min(W, (tx + 1) * T), std::min(H, (ty + 1) * T)};
    covered[tile] = mf.renderTile(rect, bins[tile]);
  }, 1);
  for (uint64_t c : covered) st.samplesCovered += c;
  st.rasterSeconds = t.seconds();
  st.totalSeconds = total.seconds();
  return res;
}

}  // namespace linesurf
