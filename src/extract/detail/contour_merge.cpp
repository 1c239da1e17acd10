// Merging of contour polylines, beyond the thesis. See contour_merge.h.
#include "contour_merge.h"

#include <algorithm>
#include <cmath>
#include <span>

#include <tbb/parallel_sort.h>

#include "linesurf/core/parallel.h"

namespace linesurf::detail {

ContourEndKey contourEndKey(uint32_t va, uint32_t vb, int64_t k, int level, int family) {
  ContourEndKey key;
  key.lo = std::min(va, vb);
  key.hi = std::max(va, vb);
  while (level > 0 && (k & 1) == 0) {  // k / 2^level in lowest terms: the levels nest (§3.3)
    k /= 2;
    --level;
  }
  key.plane = k;
  key.level = uint8_t(level);
  key.family = uint8_t(family);
  return key;
}

namespace {

// One original segment as traversed along a polyline.
struct Piece {
  uint32_t index = 0;
  bool reversed = false;  // traversed from p1 to p0
};

Vec3d startOf(const Segment& s, bool rev) { return (rev ? s.p1 : s.p0).cast<double>(); }
Vec3d endOf(const Segment& s, bool rev) { return (rev ? s.p0 : s.p1).cast<double>(); }

// `n` made perpendicular to `dir` (unit; unless `along` keeps that component), unit, on the side
// of `side`; zero when nothing is left.
Vec3d perpendicular(const Vec3d& n, const Vec3d& dir, const Vec3d& side, bool along = false) {
  Vec3d m = along ? n : Vec3d(n - n.dot(dir) * dir);
  const double l = m.norm();
  if (!(l > 1e-6)) return Vec3d::Zero();
  m /= l;
  return m.dot(side) < 0 ? Vec3d(-m) : m;
}

class ChainMerger {
 public:
  ChainMerger(const std::vector<Segment>& segs, const std::vector<Vec3f>& vn, const ContourMergeLimits& lim)
      : segs_(segs), vn_(vn), lim_(lim) {}

  // The raw vertex normal at the start of piece p (zero when unknown).
  Vec3d startNormal(const Piece& p) const { return vn_.empty() ? Vec3d::Zero() : Vec3d(vn_[2 * p.index + p.reversed].cast<double>()); }
  Vec3d endNormal(const Piece& p) const { return vn_.empty() ? Vec3d::Zero() : Vec3d(vn_[2 * p.index + !p.reversed].cast<double>()); }
  Vec2f startUv(const Piece& p) const { return p.reversed ? segs_[p.index].uv1 : segs_[p.index].uv0; }
  Vec2f endUv(const Piece& p) const { return p.reversed ? segs_[p.index].uv0 : segs_[p.index].uv1; }

  // Builds the merged segment of pieces [i, j) into `out`; false when it breaks a limit.
  bool merge(std::span<const Piece> pc, size_t i, size_t j, Segment& out) const {
    const Segment& first = segs_[pc[i].index];
    const Vec3d A = startOf(first, pc[i].reversed), B = endOf(segs_[pc[j - 1].index], pc[j - 1].reversed);
    const Vec3d C = B - A;
    const double L = C.norm();
    if (!(L > 0)) return false;
    const Vec3d dir = C / L;
    // Strip plane: the length-weighted mean of the pieces' planes, perpendicular to the chord.
    Vec3d m = Vec3d::Zero();
    Eigen::Vector4d color = Eigen::Vector4d::Zero();
    double total = 0;
    for (size_t k = i; k < j; ++k) {
      const Segment& s = segs_[pc[k].index];
      const double l = double(s.length());
      m += l * s.normal.cast<double>();
      color += l * s.color.cast<double>();
      total += l;
    }
    if (!(total > 0)) return false;
    color /= total;
    m -= m.dot(dir) * dir;
    if (!(m.norm() > 1e-6 * total)) return false;
    m.normalize();
    for (size_t k = i; k < j; ++k) {
      const Segment& s = segs_[pc[k].index];
      if (s.normal.cast<double>().dot(m) < lim_.cosStripAngle) return false;
      if ((s.color.cast<double>() - color).cwiseAbs().maxCoeff() > double(lim_.colorTolerance)) return false;
    }
    // Shading normals at the merged ends (smooth models).
    Vec3d n0 = m, n1 = m;
    if (lim_.smooth) {
      n0 = perpendicular(startNormal(pc[i]), dir, m, lim_.alongNormals);
      n1 = perpendicular(endNormal(pc[j - 1]), dir, m, lim_.alongNormals);
      if (n0 == Vec3d::Zero() || n1 == Vec3d::Zero()) return false;
    }
    const Vec2f uvA = startUv(pc[i]), uvB = endUv(pc[j - 1]);
    for (size_t k = i + 1; k < j; ++k) {  // interior vertices: start of piece k
      const Vec3d V = startOf(segs_[pc[k].index], pc[k].reversed);
      const double t = (V - A).dot(dir) / L;
      if (!(t > 0 && t < 1)) return false;
      const Vec3d e = V - (A + t * C);
      Vec3d nk = startNormal(pc[k]);
      if (!(nk.squaredNorm() > 0.25))
        nk = (segs_[pc[k - 1].index].normal + segs_[pc[k].index].normal).cast<double>().normalized();
      const double en = e.dot(nk);
      if (std::abs(en) > lim_.normalDeviation || (e - en * nk).norm() > lim_.tangentDeviation) return false;
      if (lim_.smooth) {
        const Vec3d target = perpendicular(nk, dir, m, lim_.alongNormals);
        const Vec3d interp = (n0 + t * (n1 - n0)).normalized();
        if (target == Vec3d::Zero() || interp.dot(target) < lim_.cosAngle) return false;
      }
      if (lim_.uvTolerance > 0) {
        const Vec2d uvk = startUv(pc[k]).cast<double>();
        if ((endUv(pc[k - 1]).cast<double>() - uvk).norm() > lim_.uvTolerance) return false;
        const Vec2d lin = uvA.cast<double>() + t * (uvB - uvA).cast<double>();
        if ((uvk - lin).norm() > lim_.uvTolerance) return false;
      }
    }
    out = first;
    out.p0 = A.cast<float>();
    out.p1 = B.cast<float>();
    out.normal = m.cast<float>();
    if (lim_.smooth) {
      out.normal0 = n0.cast<float>();
      out.normal1 = n1.cast<float>();
    }
    out.color = color.cast<float>();
    out.uv0 = uvA;
    out.uv1 = uvB;
    return true;
  }

 private:
  const std::vector<Segment>& segs_;
  const std::vector<Vec3f>& vn_;
  const ContourMergeLimits& lim_;
};

}  // namespace

ContourMergeCounts mergeContourPolylines(std::vector<Segment>& segments, const std::vector<ContourEndKey>& keys,
                                         const std::vector<Vec3f>& vertexNormals, const ContourMergeLimits& limits,
                                         std::vector<uint32_t>* faces) {
  const size_t n = segments.size();
  ContourMergeCounts counts;
  counts.before = n;
  // Links between ends: exactly two ends with one key, on two segments, at the same position.
  std::vector<uint32_t> order(2 * n);
  for (size_t e = 0; e < 2 * n; ++e) order[e] = uint32_t(e);
  // A total order (ties by end index): the same result from any sort and thread count.
  tbb::parallel_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return keys[a] < keys[b] || (keys[a] == keys[b] && a < b); });
  constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> link(2 * n, kNone);
  auto position = [&](uint32_t e) { return e & 1 ? segments[e / 2].p1 : segments[e / 2].p0; };
  for (size_t r = 0; r < order.size();) {
    size_t q = r + 1;
    while (q < order.size() && keys[order[q]] == keys[order[r]]) ++q;
    if (q - r == 2) {
      const uint32_t a = order[r], b = order[r + 1];
      if (a / 2 != b / 2 && position(a) == position(b)) link[a] = b, link[b] = a;
    }
    r = q;
  }

  // Polylines: walked sequentially (open ones from their free end, in index order, then the
  // closed loops), stored as runs of pieces; then merged in parallel, each into its own slots.
  std::vector<uint8_t> visited(n, 0);
  std::vector<Piece> pieces;
  pieces.reserve(n);
  std::vector<size_t> chainStart{0};
  auto walk = [&](uint32_t s, int entry) {
    for (;;) {
      visited[s] = 1;
      pieces.push_back({s, entry == 1});
      const uint32_t next = link[2 * s + (1 - entry)];
      if (next == kNone || visited[next / 2]) {
        counts.closedPolylines += next != kNone;
        break;
      }
      s = next / 2;
      entry = int(next & 1);
    }
    chainStart.push_back(pieces.size());
  };
  for (uint32_t s = 0; s < n; ++s)
    if (!visited[s] && (link[2 * s] == kNone || link[2 * s + 1] == kNone)) walk(s, link[2 * s] == kNone ? 0 : 1);
  for (uint32_t s = 0; s < n; ++s)
    if (!visited[s]) walk(s, 0);
  counts.polylines = chainStart.size() - 1;

  // Output slot of each merged segment: its lowest original index (each original is in one).
  const ChainMerger merger(segments, vertexNormals, limits);
  std::vector<Segment> out(n);
  std::vector<uint32_t> outFace(faces ? n : 0);
  std::vector<uint8_t> used(n, 0);
  parallelFor(0, counts.polylines, [&](size_t c) {
    const std::span<const Piece> chain(pieces.data() + chainStart[c], chainStart[c + 1] - chainStart[c]);
    // Greedy: from each start, the longest run of pieces that merges.
    for (size_t i = 0; i < chain.size();) {
      Segment best = segments[chain[i].index], trial;
      size_t j = i + 1;
      while (j < chain.size() && int(j + 1 - i) <= limits.maxPieces && merger.merge(chain, i, j + 1, trial)) {
        best = trial;
        ++j;
      }
      uint32_t lowest = chain[i].index;
      for (size_t k = i; k < j; ++k) lowest = std::min(lowest, chain[k].index);
      out[lowest] = best;
      used[lowest] = 1;
      if (faces) outFace[lowest] = (*faces)[chain[i].index];
      i = j;
    }
  }, 64);

  size_t kept = 0;
  for (size_t i = 0; i < n; ++i)
    if (used[i]) {
      segments[kept] = out[i];
      if (faces) (*faces)[kept] = outFace[i];
      ++kept;
    }
  segments.resize(kept);
  if (faces) faces->resize(kept);
  counts.after = segments.size();
  return counts;
}

}  // namespace linesurf::detail
