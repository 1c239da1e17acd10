// A mesh of the MLS surface (thesis §9.1; see surface/mesh_extract.h): surface following over a
// sparse cube lattice, marching tetrahedra in the Kuhn triangulation, vertices welded by edge.
#include "linesurf/surface/mesh_extract.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"

namespace linesurf {
namespace {

// Lattice coordinates take 20 bits an axis in a key: a corner (or the cell whose lowest corner it
// is) is x << 40 | y << 20 | z; an edge of the triangulation is its lower corner's key << 3 | the
// 3-bit offset to its upper corner (the Kuhn edges go from a corner to one whose coordinates are
// each equal or one more).
constexpr int kBits = 20;
constexpr int64_t kAxisCells = int64_t(1) << kBits;
constexpr uint64_t kMask = uint64_t(kAxisCells - 1);

uint64_t pack(int64_t x, int64_t y, int64_t z) { return uint64_t(x) << (2 * kBits) | uint64_t(y) << kBits | uint64_t(z); }
std::array<int64_t, 3> unpack(uint64_t k) {
  return {int64_t(k >> (2 * kBits) & kMask), int64_t(k >> kBits & kMask), int64_t(k & kMask)};
}
/// The key of the corner `bits` (x: 1, y: 2, z: 4) of the cell `cell`; no carry across axes, as
/// the lattice keeps a margin of cells on every side.
uint64_t cornerOf(uint64_t cell, int bits) {
  return cell + (uint64_t(bits & 1) << (2 * kBits)) + (uint64_t(bits >> 1 & 1) << kBits) + uint64_t(bits >> 2 & 1);
}

/// Open addressing (linear probing) from a key to a 32-bit value; ~0 is no key. Never iterated,
/// so its layout cannot reach the output.
class KeyMap {
 public:
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  explicit KeyMap(size_t expected = 1024) { rehash(std::bit_ceil(std::max<size_t>(64, 2 * expected))); }
  /// The value of `key`, or nullptr.
  const uint32_t* find(uint64_t key) const {
    for (size_t i = slot(key);; i = (i + 1) & (keys_.size() - 1)) {
      if (keys_[i] == key) return &values_[i];
      if (keys_[i] == kEmpty) return nullptr;
    }
  }
  /// Inserts key -> value unless the key is there; returns the value now held and whether it
  /// was inserted.
  std::pair<uint32_t, bool> insert(uint64_t key, uint32_t value) {
    if (2 * (size_ + 1) > keys_.size()) rehash(2 * keys_.size());
    for (size_t i = slot(key);; i = (i + 1) & (keys_.size() - 1)) {
      if (keys_[i] == key) return {values_[i], false};
      if (keys_[i] == kEmpty) {
        keys_[i] = key, values_[i] = value, ++size_;
        return {value, true};
      }
    }
  }
  size_t size() const { return size_; }
  /// Bytes per entry at the worst load (just after a doubling) with the rehash's old table.
  static constexpr double kBytesPerEntry = 12.0 * 4 * 1.5;

 private:
  size_t slot(uint64_t key) const {
    uint64_t z = key + 0x9e3779b97f4a7c15ull;  // splitmix64's finaliser
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return size_t(z ^ (z >> 31)) & (keys_.size() - 1);
  }
  void rehash(size_t capacity) {
    std::vector<uint64_t> keys(capacity, kEmpty);
    std::vector<uint32_t> values(capacity);
    std::swap(keys, keys_), std::swap(values, values_);
    size_ = 0;
    for (size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) insert(keys[i], values[i]);
  }
  std::vector<uint64_t> keys_;
  std::vector<uint32_t> values_;
  size_t size_ = 0;
};

/// The six tetrahedra of the Kuhn triangulation of the unit cube: for each order of the three
/// axes, the chain of corners from (0,0,0) to (1,1,1) adding one axis at a time. Every cube of the
/// lattice is cut the same way, so two cubes cut their common face along the same diagonal: the
/// tetrahedra tile space, and marching tetrahedra over them has no ambiguous case. Corners are
/// 3-bit (x: 1, y: 2, z: 4), listed so that each tetrahedron is positively oriented.
struct Kuhn {
  std::array<std::array<int, 4>, 6> tets{};
  Kuhn() {
    const int orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int t = 0; t < 6; ++t) {
      std::array<int, 4> v{0, 0, 0, 7};
      v[1] = 1 << orders[t][0], v[2] = v[1] | 1 << orders[t][1];
      // The orientation is the sign of the axis order as a permutation: odd orders swap the last two.
      const int* o = orders[t];
      const int inversions = (o[0] > o[1]) + (o[0] > o[2]) + (o[1] > o[2]);
      if (inversions % 2) std::swap(v[2], v[3]);
      tets[size_t(t)] = v;
    }
  }
};
const Kuhn& kuhn() {
  static const Kuhn k;
  return k;
}

/// Even permutations of (0, 1, 2, 3) that start with each index (keep a tetrahedron's orientation).
constexpr int kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
bool evenPermutation(const std::array<int, 4>& p) {
  int inversions = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) inversions += p[size_t(i)] > p[size_t(j)];
  return inversions % 2 == 0;
}

/// Bytes per visited cell: its key in the visited map and the list, two corners (map entry, value,
/// reach flag) and, on the surface, three vertices (edge map entry, position and fallback normal
/// in double while built, position and normal in float in the mesh) and six triangles. Measured
/// on Igea and a sphere at cellScale 1: 0.73 and 0.70 visited cells per source (x 1 / cellScale^2),
/// 2.0 corners, 3.0 vertices and 6.1 triangles per visited cell; the estimate takes 1 cell per
/// source, an upper bound of the order of the real figure (Igea: 135 MiB estimated, 110 MiB peak).
constexpr double kBytesPerCell = KeyMap::kBytesPerEntry + 8 + 2 * (KeyMap::kBytesPerEntry + 5) +
                                 3.1 * (KeyMap::kBytesPerEntry + 48 + 24) + 6.1 * 12;
constexpr double kCellsPerSource = 1.0;
/// The MLS surface per source: the §6.1 spacing's neighbour search (k = 12, transient), its tree,
/// normals, areas and supports.
constexpr double kSurfaceBytesPerSource = 8.0 * 12 + 128 + 64;

}  // namespace

void validate(const MeshOptions& o) {
  requireRange("cellScale", o.cellScale, 0.25, 4);
  requireRange("minWeight", o.minWeight, 0, 1);
  validate(o.mls);
  // A crossed cell's corners lie within its diagonal of the surface; past about 0.4 h they leave
  // the supports (Igea at h = 3 spacings: closed at 1.2 spacings, 34 boundary edges at 1.5, 16,336 at 2).
  if (o.cellScale > 0.4f * o.mls.supportScale)
    throwBadOption("cellScale", "must be at most 0.4 x `supportScale` (" + numberText(0.4 * o.mls.supportScale) +
                                    "): coarser cells have corners out of every support");
}

double meshBytesEstimate(const HybridModel& model, const MeshOptions& o) {
  // A point stands for about one spacing squared of surface, a segment for its strip, 2 r L,
  // against a spacing of about r: 2 L / r spacings squared.
  double area = double(model.points.size());
  for (const Segment& s : model.segments)
    if (s.radius > 0) area += 2.0 * double((s.p1 - s.p0).norm()) / double(s.radius) + 1;
  const double cells = kCellsPerSource * area / (double(o.cellScale) * double(o.cellScale));
  return double(model.points.size() + model.segments.size()) * kSurfaceBytesPerSource + cells * kBytesPerCell;
}

size_t countBoundaryEdges(const TriangleMesh& mesh) {
  std::vector<uint64_t> edges;
  edges.reserve(3 * mesh.faces.size());
  for (const auto& f : mesh.faces)
    for (int e = 0; e < 3; ++e) {
      const uint64_t a = f[size_t(e)], b = f[size_t((e + 1) % 3)];
      edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  size_t single = 0;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    single += j - i == 1;
    i = j;
  }
  return single;
}

TriangleMesh extractMesh(const HybridModel& model, const MeshOptions& o, MeshStats* statsOut, const Budget& budget) {
  validate(o);
  MeshStats st;
  st.sources = model.points.size() + model.segments.size();
  st.estimatedBytes = meshBytesEstimate(model, o);
  budget.require(budget.name(), st.estimatedBytes, fmt::format("meshing {} sources at cell {} x spacing", st.sources, o.cellScale));
  Timer timer;
  const MlsSurface surface(model, o.mls);
  st.medianSpacing = surface.medianSpacing();
  const double cell = double(o.cellScale) * st.medianSpacing;
  st.cellSize = cell;
  st.surfaceSeconds = timer.seconds();
  reportProgress(o.progress, "surface", 0.05);

  // The lattice: its origin below every source by more than the widest support (2 x the median
  // spacing x supportScale, mls.cpp's clamp) plus three cells, so that no visited cell or its
  // neighbour leaves the key's range.
  Vec3d lo = Vec3d::Constant(INFINITY), hi = Vec3d::Constant(-INFINITY);
  auto extend = [&](const Vec3f& p) { lo = lo.cwiseMin(p.cast<double>()), hi = hi.cwiseMax(p.cast<double>()); };
  for (const Point& p : model.points) extend(p.position);
  for (const Segment& s : model.segments) extend(s.p0), extend(s.p1);
  const double margin = 2.0 * double(o.mls.supportScale) * st.medianSpacing + 3 * cell;
  // Shifted by odd fractions of a cell so that no plane of lattice corners falls on a plane of the
  // data (a flat model at z = 0 would put f = 0 on the corners, and no seed cell would change sign).
  const Vec3d origin = lo - Vec3d::Constant(margin) - cell * Vec3d(0.3183, 0.2718, 0.1414);
  const double extent = ((hi - lo).maxCoeff() + 2 * margin) / cell + 3;
  if (!(extent < double(kAxisCells)))
    throwBadParameter("cellScale", fmt::format("gives {:.0f} cells along the model's longest side, more than 2^20 (raise it)", extent));
  auto cellOf = [&](const Vec3d& p) {
    const Vec3d c = ((p - origin) / cell).array().floor();
    return pack(int64_t(c.x()), int64_t(c.y()), int64_t(c.z()));
  };
  auto cornerPosition = [&](uint64_t key) {
    const auto c = unpack(key);
    return Vec3d(origin.x() + cell * double(c[0]), origin.y() + cell * double(c[1]), origin.z() + cell * double(c[2]));
  };

  // Seeds: the cells holding a source (a point, or samples half a cell apart along a segment);
  // the surface passes within a fraction of a spacing of each, so most of them straddle it.
  std::vector<uint64_t> frontier;
  frontier.reserve(model.points.size());
  for (const Point& p : model.points) frontier.push_back(cellOf(p.position.cast<double>()));
  for (const Segment& s : model.segments) {
    const Vec3d a = s.p0.cast<double>(), d = (s.p1 - s.p0).cast<double>();
    const int steps = int(std::ceil(2 * d.norm() / cell));
    for (int i = 0; i <= steps; ++i) frontier.push_back(cellOf(a + d * (double(i) / std::max(steps, 1))));
  }
  std::sort(frontier.begin(), frontier.end());
  frontier.erase(std::unique(frontier.begin(), frontier.end()), frontier.end());
  st.seedCells = frontier.size();

  // Surface following, wave by wave: evaluate the new cells' corners (in parallel, each into its
  // slot), then step across every face whose four corners, all in reach, do not share a sign
  // (a face the surface crosses: the next cell's tetrahedra continue it).
  const double minWeight = std::max(o.minWeight * st.medianSpacing * st.medianSpacing, 0.0);
  KeyMap visited(2 * frontier.size()), cornerIndex(2 * frontier.size());
  std::vector<uint64_t> cells;
  std::vector<float> value;   // f at each corner
  std::vector<uint8_t> valid;  // weight > 0 there
  for (uint64_t c : frontier) visited.insert(c, 0);
  const double expected = std::max(1.0, kCellsPerSource * double(st.seedCells));
  // The four corners of each face: axis a, side 0 (corner bit a clear) or 1.
  std::array<std::array<int, 4>, 6> faces{};
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      int k = 0;
      for (int b = 0; b < 8; ++b)
        if ((b >> a & 1) == side) faces[size_t(2 * a + side)][size_t(k++)] = b;
    }
  std::vector<uint64_t> fresh, next;
  while (!frontier.empty()) {
    fresh.clear();
    for (uint64_t c : frontier)
      for (int b = 0; b < 8; ++b)
        if (!cornerIndex.find(cornerOf(c, b))) fresh.push_back(cornerOf(c, b));
    std::sort(fresh.begin(), fresh.end());
    fresh.erase(std::unique(fresh.begin(), fresh.end()), fresh.end());
    const size_t first = value.size();
    value.resize(first + fresh.size()), valid.resize(first + fresh.size());
    parallelForRange(0, fresh.size(), [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        const MlsSample s = surface.evaluate(cornerPosition(fresh[i]), false);
        valid[first + i] = s.weight > minWeight && std::isfinite(s.value);
        value[first + i] = valid[first + i] ? float(s.value) : 0.0f;
      }
    }, 64);
    for (size_t i = 0; i < fresh.size(); ++i) cornerIndex.insert(fresh[i], uint32_t(first + i));
    next.clear();
    for (uint64_t c : frontier) {
      cells.push_back(c);
      std::array<uint32_t, 8> idx{};
      for (int b = 0; b < 8; ++b) idx[size_t(b)] = *cornerIndex.find(cornerOf(c, b));
      const auto xyz = unpack(c);
      for (int f = 0; f < 6; ++f) {
        int inside = 0, reached = 0;
        for (int b : faces[size_t(f)]) inside += value[idx[size_t(b)]] < 0, reached += valid[idx[size_t(b)]];
        if (reached < 4 || inside == 0 || inside == 4) continue;
        auto n = xyz;
        n[size_t(f / 2)] += f % 2 ? 1 : -1;
        if (n[size_t(f / 2)] < 1 || n[size_t(f / 2)] >= kAxisCells - 2) continue;
        const uint64_t key = pack(n[0], n[1], n[2]);
        if (visited.insert(key, 0).second) next.push_back(key);
      }
    }
    std::sort(next.begin(), next.end());
    std::swap(frontier, next);
    reportProgress(o.progress, "grid", std::min(0.9, 0.05 + 0.85 * double(cells.size()) / expected));
  }
  st.cells = cells.size();
  st.corners = value.size();
  st.gridSeconds = timer.seconds() - st.surfaceSeconds;

  // Marching tetrahedra over the visited cells in lattice order; a vertex per crossed edge, made
  // where the edge is first met and found again by its key.
  std::sort(cells.begin(), cells.end());
  KeyMap edgeVertex(2 * cells.size());
  std::vector<Vec3d> position;
  std::vector<Vec3d> fallbackNormal;  // inside to outside along the vertex's edge
  TriangleMesh mesh;
  const Kuhn& K = kuhn();
  for (uint64_t c : cells) {
    std::array<float, 8> f{};
    int reached = 0, inside = 0;
    for (int b = 0; b < 8; ++b) {
      const uint32_t i = *cornerIndex.find(cornerOf(c, b));
      f[size_t(b)] = value[i], reached += valid[i], inside += valid[i] && value[i] < 0;
    }
    if (inside == 0 || inside == reached) continue;
    const bool all = reached == 8;
    if (!all) {
      ++st.openCells;
      continue;
    }
    ++st.surfaceCells;
    auto vertex = [&](int a, int b) -> uint32_t {
      if (std::popcount(unsigned(a)) > std::popcount(unsigned(b))) std::swap(a, b);  // a: the lower corner
      const uint64_t key = cornerOf(c, a) << 3 | uint64_t(a ^ b);
      const auto [v, made] = edgeVertex.insert(key, uint32_t(position.size()));
      if (made) {
        const double fa = f[size_t(a)], fb = f[size_t(b)];
        const double t = fa / (fa - fb);
        const Vec3d pa = cornerPosition(cornerOf(c, a)), pb = cornerPosition(cornerOf(c, b));
        position.push_back(pa + t * (pb - pa));
        fallbackNormal.push_back((fa < 0 ? pb - pa : pa - pb).normalized());
      }
      return v;
    };
    auto emit = [&](uint32_t a, uint32_t b, uint32_t d) { mesh.faces.push_back({a, b, d}); };
    for (const auto& tet : K.tets) {
      int in = 0;
      for (int k = 0; k < 4; ++k) in += f[size_t(tet[size_t(k)])] < 0;
      if (in == 0 || in == 4) continue;
      if (in == 1 || in == 3) {
        // The lone corner first, by an even permutation: the triangle faces away from it, so an
        // inside lone corner keeps the order and an outside one reverses it.
        int lone = 0;
        for (int k = 0; k < 4; ++k)
          if ((f[size_t(tet[size_t(k)])] < 0) == (in == 1)) lone = k;
        const int* p = kEven[lone];
        const int q0 = tet[size_t(p[0])], q1 = tet[size_t(p[1])], q2 = tet[size_t(p[2])], q3 = tet[size_t(p[3])];
        const uint32_t e1 = vertex(q0, q1), e2 = vertex(q0, q2), e3 = vertex(q0, q3);
        if (in == 1) emit(e1, e2, e3);
        else emit(e1, e3, e2);
        continue;
      }
      // Two inside (a, b), two outside (c, d), (a, b, c, d) an even permutation: the quad
      // ac, ad, bd, bc faces from {a, b} to {c, d}; cut along its shorter diagonal.
      std::array<int, 4> perm{};
      int ni = 0, no = 2;
      for (int k = 0; k < 4; ++k) perm[size_t(f[size_t(tet[size_t(k)])] < 0 ? ni++ : no++)] = k;
      if (!evenPermutation(perm)) std::swap(perm[2], perm[3]);
      const int a = tet[size_t(perm[0])], b = tet[size_t(perm[1])], cc = tet[size_t(perm[2])], d = tet[size_t(perm[3])];
      const uint32_t ac = vertex(a, cc), ad = vertex(a, d), bd = vertex(b, d), bc = vertex(b, cc);
      if ((position[ac] - position[bd]).squaredNorm() <= (position[ad] - position[bc]).squaredNorm())
        emit(ac, ad, bd), emit(ac, bd, bc);
      else
        emit(ad, bd, bc), emit(ad, bc, ac);
    }
  }
  reportProgress(o.progress, "mesh", 0.95);

  // Each vertex: the gradient there is its normal; with `project`, one Newton step onto f = 0,
  // at most half a cell (a step off a flat stretch of f would leave the cell).
  const size_t nv = position.size();
  mesh.positions.resize(nv), mesh.normals.resize(nv);
  parallelForRange(0, nv, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      Vec3d x = position[i], n = fallbackNormal[i];
      const MlsSample s = surface.evaluate(x, false);
      const double g2 = s.gradient.squaredNorm();
      if (s.weight > minWeight && g2 > 0 && std::isfinite(g2)) {
        n = s.gradient / std::sqrt(g2);
        if (o.project) {
          Vec3d step = s.value * s.gradient / g2;
          const double len = step.norm();
          if (len > 0.5 * cell) step *= 0.5 * cell / len;
          x -= step;
        }
      }
      mesh.positions[i] = x.cast<float>(), mesh.normals[i] = n.cast<float>();
    }
  }, 256);
  st.vertices = nv;
  st.triangles = mesh.faces.size();
  st.boundaryEdges = countBoundaryEdges(mesh);
  st.meshSeconds = timer.seconds() - st.surfaceSeconds - st.gridSeconds;
  mesh.comments.push_back(fmt::format("linesurf mesh: MLS surface, support {} x spacing, cell {:.6g} ({} x median spacing)",
                                      o.mls.supportScale, cell, o.cellScale));
  reportProgress(o.progress, "mesh", 1.0);
  if (statsOut) *statsOut = st;
  return mesh;
}

}  // namespace linesurf
