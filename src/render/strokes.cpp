// The object-space strokes of a drawing (thesis §9.4; render/drawing.h): the model's segments
// chained at shared endpoints, the spacing between neighbouring strokes, the cross family and
// the nested priorities. Built once per model; every step runs in index order or writes its own
// slot, so the set does not depend on the thread count.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "linesurf/core/parallel.h"
#include "linesurf/render/drawing.h"

namespace linesurf {
namespace {

uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// The van der Corput sequence in base 2: the bits of j mirrored (0, 1/2, 1/4, 3/4, ... x 2^32).
uint32_t radicalInverse(uint32_t j) {
  j = (j << 16) | (j >> 16);
  j = ((j & 0x00ff00ffu) << 8) | ((j & 0xff00ff00u) >> 8);
  j = ((j & 0x0f0f0f0fu) << 4) | ((j & 0xf0f0f0f0u) >> 4);
  j = ((j & 0x33333333u) << 2) | ((j & 0xccccccccu) >> 2);
  return ((j & 0x55555555u) << 1) | ((j & 0xaaaaaaaau) >> 1);
}

std::array<uint32_t, 3> bitsOf(const Vec3f& p) {
  std::array<uint32_t, 3> k;
  for (int i = 0; i < 3; ++i) {
    const float v = p[i] == 0 ? 0.0f : p[i];  // -0 and +0 are one point
    std::memcpy(&k[i], &v, 4);
  }
  return k;
}

/// For every segment end (2 s + e), the other end it chains with: the one other end at a
/// bit-equal point of another segment; -1 where none or more than one meet (a stroke ends).
std::vector<int64_t> endPartners(const std::vector<Segment>& segs) {
  std::vector<std::pair<std::array<uint32_t, 3>, uint32_t>> ends(2 * segs.size());
  for (size_t s = 0; s < segs.size(); ++s) {
    ends[2 * s] = {bitsOf(segs[s].p0), uint32_t(2 * s)};
    ends[2 * s + 1] = {bitsOf(segs[s].p1), uint32_t(2 * s + 1)};
  }
  std::sort(ends.begin(), ends.end());
  std::vector<int64_t> partner(ends.size(), -1);
  for (size_t i = 0; i < ends.size();) {
    size_t j = i + 1;
    while (j < ends.size() && ends[j].first == ends[i].first) ++j;
    if (j - i == 2 && ends[i].second / 2 != ends[i + 1].second / 2) {
      partner[ends[i].second] = ends[i + 1].second;
      partner[ends[i + 1].second] = ends[i].second;
    }
    i = j;
  }
  return partner;
}

/// A uniform grid of sample points keyed by cell (sparse), for the neighbour queries.
class SampleGrid {
 public:
  explicit SampleGrid(float cell) : cell_(cell) {}
  struct Sample {
    Vec3f p;
    uint32_t stroke;
  };
  void add(const Vec3f& p, uint32_t stroke) { cells_[key(cellOf(p))].push_back({p, stroke}); }
  /// Calls f(sample) for every sample in the cells within `reach` cells of p's.
  template <typename F>
  void visit(const Vec3f& p, int reach, F&& f) const {
    const std::array<int64_t, 3> c = cellOf(p);
    for (int64_t dz = -reach; dz <= reach; ++dz)
      for (int64_t dy = -reach; dy <= reach; ++dy)
        for (int64_t dx = -reach; dx <= reach; ++dx) {
          auto it = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (const Sample& s : it->second)
            if (!f(s)) return;
        }
  }

 private:
  std::array<int64_t, 3> cellOf(const Vec3f& p) const {
    return {int64_t(std::floor(p.x() / cell_)), int64_t(std::floor(p.y() / cell_)), int64_t(std::floor(p.z() / cell_))};
  }
  static uint64_t key(const std::array<int64_t, 3>& c) {
    return (uint64_t(c[0] & 0x1fffff) << 42) | (uint64_t(c[1] & 0x1fffff) << 21) | uint64_t(c[2] & 0x1fffff);
  }
  float cell_;
  std::unordered_map<uint64_t, std::vector<Sample>> cells_;
};

/// Points along a stroke at most `step` apart (its pieces' ends included).
template <typename F>
void sampleStroke(const std::vector<StrokeSet::Piece>& pieces, const StrokeSet::Stroke& s, float step, F&& f) {
  for (uint32_t i = s.first; i < s.first + s.count; ++i) {
    const StrokeSet::Piece& p = pieces[i];
    const int n = std::max(1, int(std::ceil((p.b - p.a).norm() / step)));
    for (int j = i == s.first ? 0 : 1; j <= n; ++j) f(Vec3f(p.a + (p.b - p.a) * (float(j) / float(n))));
  }
}

float strokeLength(const std::vector<StrokeSet::Piece>& pieces, const StrokeSet::Stroke& s) {
  float l = 0;
  for (uint32_t i = s.first; i < s.first + s.count; ++i) l += (pieces[i].b - pieces[i].a).norm();
  return l;
}

Vec3f acrossOf(const StrokeSet::Piece& p) {
  const Vec3f t = (p.b - p.a).normalized();
  const Vec3f a = p.normal.cross(t);
  return a.norm() > 1e-6f ? Vec3f(a.normalized()) : Vec3f::Zero();
}

/// §9.4: the distance from each piece's midpoint to the nearest sample of another stroke that
/// lies across it (within 60 degrees of n x t), searched outwards in rings of `h` up to 4 h.
void measureSpacing(std::vector<StrokeSet::Piece>& pieces, const std::vector<StrokeSet::Stroke>& strokes, float h) {
  SampleGrid grid(h);
  for (size_t s = 0; s < strokes.size(); ++s)
    sampleStroke(pieces, strokes[s], 0.5f * h, [&](const Vec3f& p) { grid.add(p, uint32_t(s)); });
  std::vector<uint32_t> strokeOf(pieces.size());
  for (size_t s = 0; s < strokes.size(); ++s)
    for (uint32_t i = strokes[s].first; i < strokes[s].first + strokes[s].count; ++i) strokeOf[i] = uint32_t(s);
  parallelFor(0, pieces.size(), [&](size_t i) {
    StrokeSet::Piece& p = pieces[i];
    const Vec3f m = 0.5f * (p.a + p.b), t = (p.b - p.a).normalized();
    float best = INFINITY;
    for (int reach = 1; reach <= 4 && !(best <= float(reach) * h); ++reach)
      grid.visit(m, reach, [&](const SampleGrid::Sample& q) {
        if (q.stroke == strokeOf[i]) return true;
        const Vec3f d = q.p - m;
        const float along = std::abs(d.dot(t)), dist = d.norm();
        if (along <= 0.5f * dist) best = std::min(best, (d - d.dot(t) * t).norm());
        return true;
      });
    p.spacing = std::isfinite(best) ? std::clamp(best, 0.25f * h, 8 * h) : std::max(2 * p.radius, 0.25f * h);
  });
}

/// Nested priorities of one family (§9.4, after Praun et al. 2001's nested stroke sets): level k
/// keeps the strokes of levels < k and adds, in a seeded order, every stroke whose samples are
/// all at least r_k from the samples kept so far (r_k = h 2^(levels-1-k)); the last level takes
/// the rest. A stroke's priority is the share of the family's length ranked before it plus half
/// its own, in (level, seeded order): below a threshold f lies about the fraction f of the
/// length, spread evenly at every f.
void assignPriorities(std::vector<StrokeSet::Stroke>& strokes, size_t begin, size_t end,
                      const std::vector<StrokeSet::Piece>& pieces, float h, uint64_t seed) {
  const size_t n = end - begin;
  if (n == 0) return;
  std::vector<uint64_t> hash(n);
  for (size_t i = 0; i < n; ++i) hash[i] = splitmix(seed ^ splitmix(i + 1));
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return hash[a] != hash[b] ? hash[a] < hash[b] : a < b; });
  constexpr int kLevels = 7;
  std::vector<int> level(n, kLevels - 1);
  std::vector<uint8_t> kept(n, 0);
  std::vector<uint32_t> keptList;
  for (int k = 0; k + 1 < kLevels; ++k) {
    const float r = h * float(1 << (kLevels - 1 - k)), step = 0.25f * r;
    SampleGrid grid(r);
    for (uint32_t i : keptList) sampleStroke(pieces, strokes[begin + i], step, [&](const Vec3f& p) { grid.add(p, i); });
    std::vector<Vec3f> mine;
    for (uint32_t i : order) {
      if (kept[i]) continue;
      mine.clear();
      sampleStroke(pieces, strokes[begin + i], step, [&](const Vec3f& p) { mine.push_back(p); });
      bool free = true;
      for (const Vec3f& p : mine) {
        grid.visit(p, 1, [&](const SampleGrid::Sample& q) { return free = (q.p - p).squaredNorm() >= r * r; });
        if (!free) break;
      }
      if (!free) continue;
      kept[i] = 1, level[i] = k;
      keptList.push_back(i);
      for (const Vec3f& p : mine) grid.add(p, i);
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return level[a] < level[b]; });
  double total = 0;
  std::vector<double> len(n);
  for (size_t i = 0; i < n; ++i) total += len[i] = strokeLength(pieces, strokes[begin + i]);
  double before = 0;
  for (uint32_t i : order) {
    strokes[begin + i].priority = total > 0 ? float((before + 0.5 * len[i]) / total) : 1.0f;
    before += len[i];
  }
}

}  // namespace

StrokeSet::StrokeSet(const HybridModel& model, const DrawingOptions& options) {
  const std::vector<Segment>& segs = model.segments;
  if (segs.empty()) return;
  // 1. chains: walk back from each unvisited segment to its chain's start, then forward
  const std::vector<int64_t> partner = endPartners(segs);
  std::vector<uint8_t> visited(segs.size(), 0);
  auto pieceOf = [&](size_t s, bool reversed) {
    const Segment& g = segs[s];
    return Piece{reversed ? g.p1 : g.p0, reversed ? g.p0 : g.p1, g.normal, g.radius, 0, 0};
  };
  std::vector<std::pair<uint32_t, bool>> back, fwd;
  for (size_t s0 = 0; s0 < segs.size(); ++s0) {
    if (visited[s0]) continue;
    visited[s0] = 1;
    back.clear(), fwd.clear();
    for (int64_t e = partner[2 * s0 + 1]; e >= 0 && !visited[e / 2];) {  // forward through p1
      visited[e / 2] = 1;
      fwd.push_back({uint32_t(e / 2), e % 2 == 1});  // entered at p1: runs p1 -> p0
      e = partner[e ^ 1];
    }
    for (int64_t e = partner[2 * s0]; e >= 0 && !visited[e / 2];) {  // backward through p0
      visited[e / 2] = 1;
      back.push_back({uint32_t(e / 2), e % 2 == 0});  // reached at p0: runs p1 -> p0
      e = partner[e ^ 1];
    }
    Stroke st;
    st.first = uint32_t(pieces_.size());
    for (auto it = back.rbegin(); it != back.rend(); ++it) pieces_.push_back(pieceOf(it->first, it->second));
    pieces_.push_back(pieceOf(s0, false));
    for (const auto& [s, rev] : fwd) pieces_.push_back(pieceOf(s, rev));
    st.count = uint32_t(pieces_.size() - st.first);
    strokes_.push_back(st);
  }
  mainStrokes_ = strokes_.size();

  // 2. spacing: the typical one from the strips' widths, then each piece's own
  std::vector<float> radii;
  radii.reserve(segs.size());
  for (const Segment& g : segs) radii.push_back(g.radius);
  std::nth_element(radii.begin(), radii.begin() + long(radii.size() / 2), radii.end());
  float h = 2 * radii[radii.size() / 2];
  if (!(h > 0)) {
    const Bounds3f b = model.bounds();
    h = std::max(b.diagonal().norm() / 200.0f, 1e-6f);
  }
  measureSpacing(pieces_, strokes_, h);
  std::vector<float> sp;
  for (const Piece& p : pieces_) sp.push_back(p.spacing);
  std::nth_element(sp.begin(), sp.begin() + long(sp.size() / 2), sp.end());
  typicalSpacing_ = sp[sp.size() / 2];

  // 3. in-between strokes: every main stroke moved half its spacing across, all to the side of
  // one fixed direction (a stroke keeps one side), so neighbouring lines fill the gap between them
  std::vector<uint32_t> parent;
  if (options.style == DrawStyle::Hatch && options.inBetween) {
    const Vec3f g = Vec3f(0.27f, 0.53f, 0.80f).normalized();
    for (size_t s = 0; s < mainStrokes_; ++s) {
      float side = 0;
      for (uint32_t i = strokes_[s].first; i < strokes_[s].first + strokes_[s].count; ++i)
        side += acrossOf(pieces_[i]).dot(g) * (pieces_[i].b - pieces_[i].a).norm();
      const float sign = side < 0 ? -1.0f : 1.0f;
      Stroke st{uint32_t(pieces_.size()), strokes_[s].count, 0, Stroke::kInBetween};
      for (uint32_t i = strokes_[s].first; i < strokes_[s].first + strokes_[s].count; ++i) {
        Piece p = pieces_[i];
        const Vec3f shift = (0.5f * sign * p.spacing) * acrossOf(p);
        p.a += shift, p.b += shift;
        pieces_.push_back(p);
      }
      strokes_.push_back(st);
      parent.push_back(uint32_t(s));
    }
    inBetween_ = parent.size();
  }

  // 4. the cross family: a stroke across each main stroke (n x t, one main spacing long) every
  // typical spacing of arclength. Its priority nests along its main stroke: the j-th cross
  // stroke's is the van der Corput radical inverse of j plus a per-stroke offset, so the cross
  // strokes below f lie every 1/f-th step along every main stroke (evenly, at every f).
  std::vector<float> crossPriority;
  if (options.style == DrawStyle::Hatch && options.crossHatch) {
    const float step = typicalSpacing_;
    for (size_t s = 0; s < mainStrokes_; ++s) {
      const uint32_t offset = uint32_t(splitmix(options.strokeSeed ^ splitmix(s + 1)));
      uint32_t j = 0;
      float at = 0.5f * step, start = 0;  // arclength of the next cross stroke, of the piece's start
      for (uint32_t i = strokes_[s].first; i < strokes_[s].first + strokes_[s].count; ++i) {
        const Piece p = pieces_[i];
        const float len = (p.b - p.a).norm();
        const Vec3f a = acrossOf(p);
        for (; at < start + len; at += step, ++j) {
          if (a.isZero()) continue;
          const Vec3f m = p.a + (p.b - p.a) * ((at - start) / len);
          const Vec3f half = 0.5f * p.spacing * a;
          strokes_.push_back({uint32_t(pieces_.size()), 1, 0, Stroke::kCross});
          pieces_.push_back(Piece{m - half, m + half, p.normal, p.radius, step, p.spacing});
          crossPriority.push_back((float(radicalInverse(j + offset) >> 8) + 0.5f) / 16777216.0f);
        }
        start += len;
      }
    }
  }

  // 5. the main family's nested priorities; in-between strokes take their main stroke's
  assignPriorities(strokes_, 0, mainStrokes_, pieces_, h, options.strokeSeed);
  for (size_t i = 0; i < inBetween_; ++i) strokes_[mainStrokes_ + i].priority = strokes_[parent[i]].priority;
  const size_t firstCross = mainStrokes_ + inBetween_;
  for (size_t i = firstCross; i < strokes_.size(); ++i) strokes_[i].priority = crossPriority[i - firstCross];
}

}  // namespace linesurf
