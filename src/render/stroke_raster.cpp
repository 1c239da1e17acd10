// Silhouette tracing and stroke rasterisation of a drawing (thesis §9.4, §9.5; stroke_raster.h).
#include "stroke_raster.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "linesurf/core/parallel.h"

namespace linesurf::detail {
namespace {

bool covered(const Image& depth, int x, int y) { return depth.at(x, y).w() > 0.5f; }

/// §9.5: whether the boundary between pixels p and q is a silhouette.
bool silhouetteBetween(const Image& depth, const Image& normal, int px, int py, int qx, int qy, float focal) {
  const bool cp = covered(depth, px, py), cq = covered(depth, qx, qy);
  if (cp != cq) return true;
  if (!cp) return false;
  const float zp = depth.at(px, py).x(), zq = depth.at(qx, qy).x();
  // a depth jump: far more than a steep surface changes across one pixel (z / f object units)
  if (std::abs(zp - zq) > 16.0f * std::max(zp, zq) / focal) return true;
  if (normal.empty()) return false;
  const float np = 2 * normal.at(px, py).z() - 1, nq = 2 * normal.at(qx, qy).z() - 1;
  return (np > 0.05f && nq < -0.05f) || (np < -0.05f && nq > 0.05f);  // n.v changes sign
}

}  // namespace

std::vector<StrokeRun> traceSilhouettes(const Image& depth, const Image& normal, float focal) {
  const int w = depth.width, h = depth.height;
  // boundary edges on the lattice of pixel corners (vertex id y (w + 1) + x)
  struct Edge {
    uint32_t v0, v1;
    Vec2f mid;
  };
  std::vector<Edge> edges;
  auto vid = [w](int x, int y) { return uint32_t(y) * uint32_t(w + 1) + uint32_t(x); };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // the image border counts as uncovered: a model cut by the frame keeps its outline open
      if (x + 1 < w ? silhouetteBetween(depth, normal, x, y, x + 1, y, focal) : false)
        edges.push_back({vid(x + 1, y), vid(x + 1, y + 1), Vec2f(float(x + 1), y + 0.5f)});
      if (y + 1 < h ? silhouetteBetween(depth, normal, x, y, x, y + 1, focal) : false)
        edges.push_back({vid(x, y + 1), vid(x + 1, y + 1), Vec2f(x + 0.5f, float(y + 1))});
    }
  std::vector<StrokeRun> out;
  if (edges.empty()) return out;
  // the edges at each corner (at most four)
  std::vector<uint32_t> order(edges.size() * 2);
  for (uint32_t i = 0; i < edges.size(); ++i) order[2 * i] = 2 * i, order[2 * i + 1] = 2 * i + 1;
  auto vertexOf = [&](uint32_t end) { return end % 2 ? edges[end / 2].v1 : edges[end / 2].v0; };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return vertexOf(a) != vertexOf(b) ? vertexOf(a) < vertexOf(b) : a < b;
  });
  std::vector<int64_t> partner(order.size(), -1);
  for (size_t i = 0; i < order.size();) {
    size_t j = i + 1;
    while (j < order.size() && vertexOf(order[j]) == vertexOf(order[i])) ++j;
    if (j - i == 2) partner[order[i]] = order[i + 1], partner[order[i + 1]] = order[i];
    i = j;
  }
  std::vector<uint8_t> seen(edges.size(), 0);
  std::vector<Vec2f> back;
  for (uint32_t e0 = 0; e0 < edges.size(); ++e0) {
    if (seen[e0]) continue;
    seen[e0] = 1;
    StrokeRun run;
    run.stroke = StrokeRun::kSilhouette;
    // forward through v1 first: a closed outline comes back to e0 there
    std::vector<Vec2f> fwd;
    int64_t e = partner[2 * e0 + 1];
    for (; e >= 0 && !seen[e / 2]; e = partner[e ^ 1]) seen[e / 2] = 1, fwd.push_back(edges[e / 2].mid);
    const bool closed = e >= 0 && e / 2 == int64_t(e0);
    back.clear();
    for (e = partner[2 * e0]; e >= 0 && !seen[e / 2]; e = partner[e ^ 1]) seen[e / 2] = 1, back.push_back(edges[e / 2].mid);
    run.points.assign(back.rbegin(), back.rend());
    run.points.push_back(edges[e0].mid);
    run.points.insert(run.points.end(), fwd.begin(), fwd.end());
    if (closed) run.points.push_back(edges[e0].mid);
    if (run.points.size() == 1) {  // one boundary edge: its own length
      const Edge& g = edges[e0];
      const bool vertical = g.v1 - g.v0 != 1;
      run.points = {g.mid - (vertical ? Vec2f(0, 0.5f) : Vec2f(0.5f, 0)), g.mid + (vertical ? Vec2f(0, 0.5f) : Vec2f(0.5f, 0))};
    }
    out.push_back(std::move(run));
  }
  return out;
}

namespace {

/// Box-filtered coverage of a pixel whose centre is `d` pixels from a stroke's centre line:
/// the overlap of the pixel's extent across the stroke with the stroke's width (ink per unit
/// length is then exactly the width, at any sub-pixel position).
float coverage(float d, float width) {
  return std::max(0.0f, std::min(d + 0.5f, 0.5f * width) - std::max(d - 0.5f, -0.5f * width));
}

float distanceToSegment(const Vec2f& p, const Vec2f& a, const Vec2f& b) {
  const Vec2f ab = b - a;
  const float l2 = ab.squaredNorm();
  const float t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0f, 1.0f) : 0.0f;
  return (p - (a + t * ab)).norm();
}

}  // namespace

Image rasterRuns(const std::vector<StrokeRun>& runs, int width, int height, float strokeWidth, const Color& paperColor,
                 const Color& inkColor) {
  constexpr int kTile = 64;
  const int tilesX = (width + kTile - 1) / kTile, tilesY = (height + kTile - 1) / kTile;
  const float reach = 0.5f * strokeWidth + 1.0f;
  // (tile, run) pairs, sorted: each tile draws its runs in run order
  std::vector<std::pair<uint32_t, uint32_t>> bins;
  for (uint32_t r = 0; r < runs.size(); ++r) {
    const std::vector<Vec2f>& pts = runs[r].points;
    float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (const Vec2f& p : pts) x0 = std::min(x0, p.x()), y0 = std::min(y0, p.y()), x1 = std::max(x1, p.x()), y1 = std::max(y1, p.y());
    const int tx0 = std::max(0, int(std::floor((x0 - reach) / kTile))), tx1 = std::min(tilesX - 1, int(std::floor((x1 + reach) / kTile)));
    const int ty0 = std::max(0, int(std::floor((y0 - reach) / kTile))), ty1 = std::min(tilesY - 1, int(std::floor((y1 + reach) / kTile)));
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) bins.push_back({uint32_t(ty * tilesX + tx), r});
  }
  std::sort(bins.begin(), bins.end());
  std::vector<size_t> tileStart(size_t(tilesX) * tilesY + 1, bins.size());
  for (size_t i = bins.size(); i-- > 0;) tileStart[bins[i].first] = i;
  for (size_t t = tileStart.size() - 1; t-- > 0;) tileStart[t] = std::min(tileStart[t], tileStart[t + 1]);

  std::vector<float> transmit(size_t(width) * height, 1.0f);
  const float inkAlpha = inkColor.w();
  parallelFor(0, size_t(tilesX) * tilesY, [&](size_t tile) {
    const int bx0 = int(tile % tilesX) * kTile, by0 = int(tile / tilesX) * kTile;
    const int bx1 = std::min(width, bx0 + kTile), by1 = std::min(height, by0 + kTile);
    std::vector<float> cov(size_t(kTile) * kTile, 0.0f);
    std::vector<uint32_t> touched;
    for (size_t i = tileStart[tile]; i < tileStart[tile + 1]; ++i) {
      const std::vector<Vec2f>& pts = runs[bins[i].second].points;
      for (size_t k = 0; k + 1 < pts.size(); ++k) {
        const Vec2f a = pts[k], b = pts[k + 1];
        const int x0 = std::max(bx0, int(std::floor(std::min(a.x(), b.x()) - reach)));
        const int x1 = std::min(bx1 - 1, int(std::floor(std::max(a.x(), b.x()) + reach)));
        const int y0 = std::max(by0, int(std::floor(std::min(a.y(), b.y()) - reach)));
        const int y1 = std::min(by1 - 1, int(std::floor(std::max(a.y(), b.y()) + reach)));
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            const float c = coverage(distanceToSegment(Vec2f(x + 0.5f, y + 0.5f), a, b), strokeWidth);
            if (c <= 0) continue;
            const uint32_t p = uint32_t((y - by0) * kTile + (x - bx0));
            if (cov[p] == 0) touched.push_back(p);
            cov[p] = std::max(cov[p], c);
          }
      }
      for (uint32_t p : touched) {  // one run darkens a pixel once, however many pieces reach it
        const size_t px = size_t(by0 + int(p / kTile)) * width + size_t(bx0 + int(p % kTile));
        transmit[px] *= 1.0f - std::min(1.0f, cov[p]) * inkAlpha;
        cov[p] = 0;
      }
      touched.clear();
    }
  }, 1);

  Image img(width, height);
  const Vec3f paper = paperColor.head<3>(), ink = inkColor.head<3>();
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    const float t = transmit[i], alpha = paperColor.w() * t + (1 - t);
    const Vec3f rgb = alpha > 0 ? Vec3f((paper * (paperColor.w() * t) + ink * (1 - t)) / alpha) : Vec3f::Zero();
    img.pixels[i] = Color(rgb.x(), rgb.y(), rgb.z(), alpha);
  }
  return img;
}

}  // namespace linesurf::detail
