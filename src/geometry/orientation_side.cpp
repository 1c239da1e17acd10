// Which side a component's normals face (see detail/orientation_side.h).
#include "geometry/detail/orientation_side.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "linesurf/core/parallel.h"

namespace linesurf::detail {
namespace {

constexpr int kColumns = 64;  // cells along the longest axis

int32_t quantised(double x) { return int32_t(std::lround(1024.0 * x)); }

bool farther(const SideEntry& a, const SideEntry& b) { return a.value > b.value || (a.value == b.value && a.index < b.index); }

// The view from above counts twice under `auto`: an open sheet (terrain) has the same points on
// top of its columns from above and below, whose votes would cancel.
int64_t directionWeight(OrientSide rule, uint32_t key) { return rule == OrientSide::Auto && (key >> 24) == 0 ? 2 : 1; }

}  // namespace

SideGrid::SideGrid(const Bounds3f& bounds) {
  if (bounds.empty()) return;
  lo_ = bounds.min;
  const Vec3f ext = bounds.diagonal();
  const float longest = ext.maxCoeff();
  cell_ = longest > 0 ? longest / float(kColumns) : 1.0f;
  for (int a = 0; a < 3; ++a) dims_[size_t(a)] = std::clamp(int(std::ceil(ext[a] / cell_)), 1, kColumns);
}

int SideGrid::cellOf(float v, int a) const {
  const float f = std::floor((v - lo_[a]) / cell_);
  return f < 0 ? 0 : f >= float(dims_[size_t(a)]) ? dims_[size_t(a)] - 1 : int(f);
}

uint32_t SideGrid::key(const Vec3f& p, int dir) const {
  const int axis = dir == 0 || dir == 1 ? 2 : dir == 2 || dir == 3 ? 0 : 1;
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  return uint32_t(dir) << 24 | uint32_t(cellOf(p[b], b) * dims_[size_t(c)] + cellOf(p[c], c));
}

std::vector<SideSummary> sideSummaries(OrientSide rule, const Vec3f& viewpoint, const SideGrid& grid, std::span<const Vec3f> pos,
                                       std::span<const Vec3f> normal, std::span<const uint32_t> comp, size_t components,
                                       std::span<const uint64_t> index, std::span<const uint8_t> take) {
  std::vector<SideSummary> out(components);
  const size_t n = pos.size();
  auto indexOf = [&](size_t t) { return index.empty() ? uint64_t(t) : index[t]; };
  auto taken = [&](size_t t) { return take.empty() || take[t] != 0; };
  for (size_t t = 0; t < n; ++t) {
    if (!taken(t)) continue;
    SideSummary& s = out[comp[t]];
    if (indexOf(t) < s.firstIndex) s.firstIndex = indexOf(t), s.firstNormal = normal[t];
  }
  if (rule == OrientSide::Up || rule == OrientSide::Towards || rule == OrientSide::AwayFrom) {
    for (size_t t = 0; t < n; ++t) {
      if (!taken(t)) continue;
      double v;
      if (rule == OrientSide::Up) {
        v = double(normal[t].z());
      } else {
        const Vec3d d = (viewpoint - pos[t]).cast<double>();
        const double len = d.norm();
        v = len > 0 ? normal[t].cast<double>().dot(d) / len : 0.0;
      }
      out[comp[t]].vote += quantised(v);
    }
    return out;
  }
  // Columns: per direction, a map (component, column) -> the farthest point so far. The
  // directions are independent, so they run in parallel with the same result.
  std::array<std::vector<std::pair<uint64_t, SideEntry>>, 6> found;
  parallelFor(0, 6, [&](size_t dir) {
    const Vec3f& d = kSideDirections[dir];
    const int axis = dir < 2 ? 2 : dir < 4 ? 0 : 1;
    const float sign = dir % 2 == 0 ? 1.0f : -1.0f;
    std::unordered_map<uint64_t, SideEntry> best;
    for (size_t t = 0; t < n; ++t) {
      if (!taken(t)) continue;
      const SideEntry e{grid.key(pos[t], int(dir)), sign * pos[t][axis], indexOf(t), quantised(double(normal[t].dot(d)))};
      auto [it, fresh] = best.try_emplace(uint64_t(comp[t]) << 32 | e.key, e);
      if (!fresh && farther(e, it->second)) it->second = e;
    }
    found[dir].assign(best.begin(), best.end());
    std::sort(found[dir].begin(), found[dir].end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  }, 1);
  // Directions in order, each by (component, column): every envelope ascends by key.
  for (const auto& f : found)
    for (const auto& [k, e] : f) out[size_t(k >> 32)].envelope.push_back(e);
  return out;
}

void mergeSides(SideSummary& a, const SideSummary& b, bool flip) {
  const int64_t sign = flip ? -1 : 1;
  a.vote += sign * b.vote;
  if (b.firstIndex < a.firstIndex) a.firstIndex = b.firstIndex, a.firstNormal = flip ? Vec3f(-b.firstNormal) : b.firstNormal;
  std::vector<SideEntry> merged;
  merged.reserve(a.envelope.size() + b.envelope.size());
  size_t i = 0, j = 0;
  while (i < a.envelope.size() || j < b.envelope.size()) {
    if (j == b.envelope.size() || (i < a.envelope.size() && a.envelope[i].key < b.envelope[j].key)) {
      merged.push_back(a.envelope[i++]);
      continue;
    }
    SideEntry e = b.envelope[j++];
    e.vote = int32_t(sign * e.vote);
    if (i < a.envelope.size() && a.envelope[i].key == e.key) {
      if (!farther(e, a.envelope[i])) e = a.envelope[i];
      ++i;
    }
    merged.push_back(e);
  }
  a.envelope.swap(merged);
}

bool flipForSide(const SideSummary& s, OrientSide rule) {
  int64_t score = 0;
  if (rule == OrientSide::Auto || rule == OrientSide::Outward) {
    for (const SideEntry& e : s.envelope) score += directionWeight(rule, e.key) * e.vote;
  } else {
    score = rule == OrientSide::AwayFrom ? -s.vote : s.vote;
  }
  if (score != 0) return score < 0;
  int i = 0;
  s.firstNormal.cwiseAbs().maxCoeff(&i);
  return s.firstNormal[i] < 0;
}

}  // namespace linesurf::detail
