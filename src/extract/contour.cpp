// Contour-plane extraction, thesis §3.3. See include/linesurf/extract/contour.h and
// docs/decisions.md ("Contour-plane extraction (§3.3)") for the rules chosen here.
#include "linesurf/extract/contour.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/core/mesh_normals.h"
#include "detail/contour_merge.h"

namespace linesurf {
namespace {


/// Smooth models: the plane of a strip or point follows the interpolated normal `n` (unit) but
/// leans at most kMaxTiltDegrees away from its triangle's normal `fn` (unit): back-face culling
/// decides by this plane, and a plane leaning further than the triangle's grazing angle culls a
/// visible triangle (Al's shoe soles at a 90-degree crease; background pixels where the mesh is
/// covered, 20 views: 31 lines / 61 points at 10 degrees, 394 / 443 at 20, 1,162 / 1,327
/// unlimited; docs/decisions.md). Both vectors are perpendicular to the segment, so the result is.
constexpr double kMaxTiltDegrees = 10.0;
double maxTiltCos() { return std::cos(kMaxTiltDegrees * 3.14159265358979323846 / 180.0); }
Vec3d limitTilt(const Vec3d& n, const Vec3d& fn) {
  const double c = n.dot(fn), cmax = maxTiltCos();
  if (c >= cmax) return n;
  Vec3d side = n - c * fn;
  const double sl = side.norm();
  if (!(sl > 1e-12)) return fn;
  return cmax * fn + std::sqrt(1 - cmax * cmax) * (side / sl);
}

// splitmix64: a tiny, fully specified generator, so a seed gives the same planes everywhere
// (std:: distributions differ between standard libraries).
uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
double uniform01(uint64_t& state) { return double(splitmix64(state) >> 11) * 0x1.0p-53; }

// Polyline merging: the merged segment's colour (length-weighted mean) stays within this of every
// piece's colour, per channel (about 2/255: below what an 8-bit image shows).
constexpr float kMergeColorTolerance = 0.008f;

constexpr size_t kBlock = 4096;  // fixed blocks: deterministic partial sums for any thread count

// A cut endpoint on edge (a, b) of a face (local corners 0..2), point = P_a + lambda (P_b - P_a),
// with a the corner of lower plane value, so both faces sharing the edge compute the same bits.
struct EdgePoint {
  int a = 0, b = 0;
  double lambda = 0;
  int64_t plane = 0;  // k: plane k of the face's level
};

struct FaceInfo {
  uint8_t family = 0;
  uint8_t level = 0;
  bool degenerate = false;
  bool touch = false;      // a plane touches only the face's top vertex
  uint32_t converted = 0;  // segments of this face turned into points
};

class Cutter {
 public:
  Cutter(const TriangleMesh& mesh, const ContourOptions& o, double d, const std::vector<double>* values)
      : mesh_(mesh), opt_(o), d_(d), values_(values) {}

  // Plane values of a face's corners at its level, and the order of the corners by value.
  struct Sorted {
    double t[3];
    int o[3] = {0, 1, 2};
    int64_t kLo = 0, kHi = -1;  // planes t0 < k <= t2
    bool topTouch = false;      // plane kHi only touches the top vertex
    size_t cuts() const { return kHi >= kLo ? size_t(kHi - kLo + 1) - size_t(topTouch) : 0; }
  };
  Sorted sorted(size_t f, const FaceInfo& info) const {
    const auto& F = mesh_.faces[f];
    const std::vector<double>& val = values_[info.family];
    Sorted s;
    const double scale = double(uint64_t(1) << info.level);  // 2^m: exact, so levels nest
    for (int c = 0; c < 3; ++c) s.t[c] = val[F[c]] * scale;
    int* o = s.o;
    const double* t = s.t;
    // Stable 3-sort by plane value (ties keep corner order; the results do not depend on it).
    if (t[o[1]] < t[o[0]]) std::swap(o[0], o[1]);
    if (t[o[2]] < t[o[1]]) std::swap(o[1], o[2]);
    if (t[o[1]] < t[o[0]]) std::swap(o[0], o[1]);
    const double t0 = t[o[0]], t1 = t[o[1]], t2 = t[o[2]];
    // Symbolic rule: a vertex exactly on a plane counts as above it. Plane k cuts the face iff
    // t0 < k <= t2, and the crossings are on the edges whose lower end is below and upper end
    // is on or above, so a plane through a shared edge or vertex is cut exactly once.
    s.kLo = int64_t(std::floor(t0)) + 1;
    s.kHi = int64_t(std::floor(t2));
    // Only the top vertex on plane kHi: a single point, no segment.
    s.topTouch = s.kHi >= s.kLo && double(s.kHi) == t2 && t1 < t2;
    return s;
  }

  // Calls emit(A, B, P0, P1) for every plane of the face's lattice that cuts it along a segment
  // of positive extent, in increasing plane order.
  template <class Emit>
  void cut(size_t f, const FaceInfo& info, Emit&& emit) const {
    const Sorted s = sorted(f, info);
    const auto& F = mesh_.faces[f];
    Vec3d P[3];
    for (int c = 0; c < 3; ++c) P[c] = mesh_.positions[F[c]].cast<double>();
    auto point = [&](int a, int b, double k) {
      EdgePoint e{a, b, (k - s.t[a]) / (s.t[b] - s.t[a]), int64_t(k)};
      Vec3f p = (P[a] + e.lambda * (P[b] - P[a])).cast<float>();
      return std::pair{e, p};
    };
    const int64_t kEnd = s.kHi - int64_t(s.topTouch);
    const double t1 = s.t[s.o[1]];
    for (int64_t k = s.kLo; k <= kEnd; ++k) {
      const double kd = double(k);
      auto [ea, pa] = point(s.o[0], s.o[2], kd);
      auto [eb, pb] = kd <= t1 ? point(s.o[0], s.o[1], kd) : point(s.o[1], s.o[2], kd);
      emit(ea, eb, pa, pb);
    }
  }

  // Number of points a segment of length l becomes: ⌈l/d⌉ + 1 (thesis §3.3, read with l for
  // the "1" of the printed formula), so that neighbouring points are at most d apart.
  size_t pointsFor(double length) const {
    return size_t(std::min(std::ceil(length / d_), 0x1.0p40)) + 1;  // clamp: the total is checked
  }
  bool toPoints(double length) const { return opt_.allPoints || length < double(opt_.pointsBelow); }

 private:
  const TriangleMesh& mesh_;
  const ContourOptions& opt_;
  double d_;
  const std::vector<double>* values_;
};

// Per-face attribute interpolation at barycentric weights w (corner order of the face).
struct Interpolator {
  const TriangleMesh& mesh;
  const std::vector<Vec3f>& unitVertexNormals;  // empty unless vertex normals are used
  bool textured = false, vertexColors = false, texcoords = false;

  Vec2f uv(size_t f, const double w[3]) const {
    const auto& c = mesh.cornerUVs[f];
    return (w[0] * c[0].cast<double>() + w[1] * c[1].cast<double>() + w[2] * c[2].cast<double>()).cast<float>();
  }
  Color color(size_t f, const double w[3]) const {
    if (textured) {
      Vec2f t = uv(f, w);
      return mesh.texture->sampleBilinear(t.x(), t.y());
    }
    if (vertexColors) {
      const auto& F = mesh.faces[f];
      Eigen::Vector4d c = w[0] * mesh.colors[F[0]].cast<double>() + w[1] * mesh.colors[F[1]].cast<double>() +
                w[2] * mesh.colors[F[2]].cast<double>();
      return c.cast<float>();
    }
    return Color(1, 1, 1, 1);
  }
  // Interpolated unit vertex normal, or zero when it vanishes.
  Vec3d vertexNormal(size_t f, const double w[3]) const {
    const auto& F = mesh.faces[f];
    Vec3d n = w[0] * unitVertexNormals[F[0]].cast<double>() + w[1] * unitVertexNormals[F[1]].cast<double>() +
              w[2] * unitVertexNormals[F[2]].cast<double>();
    double len = n.norm();
    return len > 1e-12 ? Vec3d(n / len) : Vec3d::Zero();
  }
};

// The least point mass written: a point standing for (almost) no length still weighs something, so
// that every point is a valid splat (the masses must be > 0).
constexpr double kMinPointMass = 1e-3;

void weightsOf(const EdgePoint& e, double w[3]) {
  w[0] = w[1] = w[2] = 0;
  w[e.a] = 1 - e.lambda;
  w[e.b] += e.lambda;
}

void checkContourOptions(const ContourOptions& o) {
  if (!(o.spacing >= 0 && o.spacing <= 1e30))
    throwBadOption("spacing", fmt::format("must be a length in [0, 1e30] (0 = from the mean edge length), got {}", o.spacing));
  if (o.spacing == 0 && !(o.spacingScale > 0 && o.spacingScale <= 1e6))
    throwBadOption("spacingScale", fmt::format("must be in (0, 1e6], got {}", o.spacingScale));
  if (!(std::isfinite(o.diagonalDivisions) && o.diagonalDivisions >= 0 && o.diagonalDivisions <= 1e6))
    throwBadOption("diagonalDivisions", fmt::format("must be in [0, 1e6] (0 = no cap on d), got {}", o.diagonalDivisions));
  // Radii beyond 100 d overflow the model's bounds by orders of magnitude: refused here, before the work.
  if (!(o.radiusScale > 0 && o.radiusScale <= 100))
    throwBadOption("radiusScale", fmt::format("must be in (0, 100] (> 0.5 for a hole-free model), got {}", o.radiusScale));
  if (!(o.pointsBelow >= 0 && o.pointsBelow <= 1e30))
    throwBadOption("pointsBelow", fmt::format("must be a length in [0, 1e30], got {}", o.pointsBelow));
  if (o.allPoints && o.pointsBelow > 0)
    throwBadOption("pointsBelow", "conflicts with `allPoints`: choose one");
  if (!(o.familySwitchSine >= 0 && o.familySwitchSine <= 1))
    throwBadOption("familySwitchSine", fmt::format("must be in [0, 1], got {}", o.familySwitchSine));
  if (!(o.mergeNormalDeviation >= 0 && o.mergeNormalDeviation <= 1e6))
    throwBadOption("mergeNormalDeviation", fmt::format("must be a multiple of d in [0, 1e6] (0 = no merging), got {}", o.mergeNormalDeviation));
  if (!(o.mergeTangentDeviation >= 0 && o.mergeTangentDeviation <= 1e6))
    throwBadOption("mergeTangentDeviation", fmt::format("must be a multiple of d in [0, 1e6], got {}", o.mergeTangentDeviation));
  if (!(std::isfinite(o.mergeAngle) && o.mergeAngle >= 0 && o.mergeAngle < 90))
    throwBadOption("mergeAngle", fmt::format("must be in [0, 90) degrees, got {}", o.mergeAngle));
  if (!(std::isfinite(o.mergeStripAngle) && o.mergeStripAngle >= 0 && o.mergeStripAngle < 90))
    throwBadOption("mergeStripAngle", fmt::format("must be in [0, 90) degrees, got {}", o.mergeStripAngle));
  if (o.mergeMaxPieces < 1 || o.mergeMaxPieces > 1024)
    throwBadOption("mergeMaxPieces", fmt::format("must be in [1, 1024], got {}", o.mergeMaxPieces));
  if (o.planes) {
    for (int f = 0; f < 2; ++f)
      if (!o.planes->normal[f].allFinite() || std::abs(o.planes->normal[f].norm() - 1) > 1e-6 ||
          !std::isfinite(o.planes->offset[f]))
        throwBadParameter("planes", fmt::format("family {} needs a finite unit normal and a finite offset", f));
    if (std::abs(o.planes->normal[0].dot(o.planes->normal[1])) > 1e-6)
      throwBadParameter("planes", "the two plane families must be perpendicular");
  }
}

void validate(const TriangleMesh& mesh, const ContourOptions& o) {
  checkContourOptions(o);
  const size_t nv = mesh.positions.size();
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (uint32_t v : mesh.faces[f])
      if (v >= nv)
        throwBadInput("mesh", fmt::format("face {}", f), fmt::format("vertex index {} out of range ({} vertices)", v, nv));
  if (!mesh.cornerUVs.empty() && mesh.cornerUVs.size() != mesh.faces.size())
    throwBadInput("mesh", "texcoords", fmt::format("{} per-corner uv triples for {} faces", mesh.cornerUVs.size(), mesh.faces.size()));
  if (!mesh.colors.empty() && mesh.colors.size() != nv)
    throwBadInput("mesh", "colors", fmt::format("{} vertex colours for {} vertices", mesh.colors.size(), nv));
  if (!mesh.normals.empty() && mesh.normals.size() != nv)
    throwBadInput("mesh", "normals", fmt::format("{} vertex normals for {} vertices", mesh.normals.size(), nv));
}

// Runs f(begin, end) over [0, n) in blocks, reporting progress between blocks from this thread.
template <class F>
void blockedWithProgress(size_t n, const ProgressFn& progress, double from, double to, F&& f) {
  const size_t step = std::max<size_t>(65536, n / 20 + 1);
  for (size_t b = 0; b < n; b += step) {
    size_t e = std::min(n, b + step);
    parallelForRange(b, e, f, 1024);
    reportProgress(progress, "contour planes", from + (to - from) * double(e) / double(n));
  }
}

}  // namespace

void validate(const ContourOptions& options) { checkContourOptions(options); }

double contourSpacing(const ContourOptions& options, double meanEdgeLength, double diagonal, bool* capped) {
  if (capped) *capped = false;
  if (options.spacing > 0) return double(options.spacing);
  double base = meanEdgeLength;
  if (options.diagonalDivisions > 0 && diagonal > 0 && std::isfinite(diagonal)) {
    const double cap = diagonal / double(options.diagonalDivisions);
    if (cap < base) {
      base = cap;
      if (capped) *capped = true;
    }
  }
  return double(options.spacingScale) * base;
}

ContourPlanes randomContourPlanes(uint64_t seed, double spacing) {
  uint64_t state = seed ^ 0x6C696E6573757266ull;  // "linesurf"
  ContourPlanes planes;
  for (int attempt = 0; attempt < 10000; ++attempt) {
    // Uniform random rotation (Shoemake's unit quaternion).
    double u1 = uniform01(state), u2 = uniform01(state), u3 = uniform01(state);
    const double twoPi = 2 * std::numbers::pi;
    Eigen::Quaterniond q(std::sqrt(u1) * std::cos(twoPi * u3), std::sqrt(1 - u1) * std::sin(twoPi * u2),
                         std::sqrt(1 - u1) * std::cos(twoPi * u2), std::sqrt(u1) * std::sin(twoPi * u3));
    Mat3d r = q.normalized().toRotationMatrix();
    planes.normal[0] = r.col(2);
    planes.normal[1] = r.col(0);
    // Not aligned with the model's axes (§3.3): each normal at least ~25.8° from every axis.
    if (planes.normal[0].cwiseAbs().maxCoeff() < 0.9 && planes.normal[1].cwiseAbs().maxCoeff() < 0.9) break;
  }
  planes.offset[0] = uniform01(state) * spacing;
  planes.offset[1] = uniform01(state) * spacing;
  return planes;
}

HybridModel extractContour(const TriangleMesh& mesh, const ContourOptions& options, ContourStats* statsOut) {
  Timer timer;
  validate(mesh, options);
  ContourStats stats;
  const size_t nf = mesh.faces.size(), nv = mesh.positions.size();
  stats.triangles = nf;

  // Pass A: unit face normals, degeneracy, edge lengths (fixed blocks: deterministic sums).
  std::vector<Vec3f> faceNormal(nf);
  std::vector<FaceInfo> info(nf);
  const size_t nBlocks = (nf + kBlock - 1) / kBlock;
  std::vector<double> edgeSum(nBlocks, 0);
  std::vector<size_t> edgeFaces(nBlocks, 0);
  parallelFor(0, nBlocks, [&](size_t blk) {
    double sum = 0;
    size_t count = 0;
    for (size_t f = blk * kBlock, e = std::min(nf, f + kBlock); f < e; ++f) {
      const auto& F = mesh.faces[f];
      Vec3d a = mesh.positions[F[0]].cast<double>(), b = mesh.positions[F[1]].cast<double>(),
            c = mesh.positions[F[2]].cast<double>();
      Vec3d n = (b - a).cross(c - a);  // in double from float input: slivers keep a good normal
      double l0 = (b - a).norm(), l1 = (c - b).norm(), l2 = (a - c).norm();
      double maxEdge = std::max({l0, l1, l2});
      double area2 = n.norm();
      if (!(area2 > 1e-12 * maxEdge * maxEdge) || !std::isfinite(area2)) {
        info[f].degenerate = true;
        continue;
      }
      faceNormal[f] = (n / area2).cast<float>();
      sum += l0 + l1 + l2;
      count += 3;
    }
    edgeSum[blk] = sum;
    edgeFaces[blk] = count;
  }, 1);
  double edgeTotal = 0;
  size_t edgeCount = 0;
  for (size_t b = 0; b < nBlocks; ++b) edgeTotal += edgeSum[b], edgeCount += edgeFaces[b];
  for (size_t f = 0; f < nf; ++f) stats.degenerateTriangles += info[f].degenerate;
  stats.meanEdgeLength = edgeCount ? edgeTotal / double(edgeCount) : 0;

  HybridModel model;
  model.comments = mesh.comments;
  {
    const Bounds3f box = mesh.bounds();
    stats.diagonal = box.empty() ? 0.0 : double(box.diagonal().norm());
  }
  const double d = contourSpacing(options, stats.meanEdgeLength, stats.diagonal, &stats.spacingFromDiagonal);
  stats.spacing = d;
  stats.radius = double(options.radiusScale) * d;
  if (!(d > 0) || !std::isfinite(d)) {  // nothing to cut: no non-degenerate face
    stats.seconds = timer.seconds();
    if (statsOut) *statsOut = std::move(stats);
    return model;
  }
  stats.planes = options.planes ? *options.planes : randomContourPlanes(options.seed, d);
  const ContourPlanes& planes = stats.planes;

  // Plane values of every vertex, in units of d: shared by all faces, so a vertex on a plane
  // is on it for every face around it.
  std::vector<double> values[2];
  for (int fam = 0; fam < 2; ++fam) values[fam].resize(nv);
  parallelFor(0, nv, [&](size_t v) {
    Vec3d p = mesh.positions[v].cast<double>();
    for (int fam = 0; fam < 2; ++fam) values[fam][v] = (planes.normal[fam].dot(p) - planes.offset[fam]) / d;
  }, 4096);
  // Plane indices must stay exact integers in a double (and fit int64): |value| 2^m < 2^52.
  constexpr double kExact = 0x1.0p52;
  double maxValue = 0;
  for (int fam = 0; fam < 2; ++fam)
    for (double x : values[fam])
      if (std::isfinite(x)) maxValue = std::max(maxValue, std::abs(x));
  if (maxValue >= kExact / 4)
    throwBadParameter("spacing", fmt::format("d = {:.6g} is too small for coordinates up to {:.6g} (plane indices beyond 2^50)",
                                             d, maxValue * d));

  // Unit vertex normals: the mesh's own, or area-weighted ones for smooth line models.
  const bool useVertexNormals = options.vertexNormals && mesh.normals.size() == nv && nv > 0;
  const bool smooth = options.endpointNormals && nv > 0;
  const bool shading = smooth && options.shadingNormals;  // full normals for lighting
  std::vector<Vec3f> unitVertexNormals;
  if (useVertexNormals || smooth) unitVertexNormals = meshVertexNormals(mesh);

  const bool convert = options.allPoints || options.pointsBelow > 0;
  Cutter cutter(mesh, options, d, values);

  // Pass B: family and level per face (§3.3: d(P) = d / 2^⌈log2(1/sin θ)⌉), output counts.
  // Counts go to offset[f + 1] and become offsets by an in-place prefix sum below.
  std::vector<size_t> segOffset(nf + 1, 0), ptOffset(convert ? nf + 1 : 0, 0);
  auto segCount = [&](size_t f) { return segOffset[f + 1] - segOffset[f]; };
  auto ptCount = [&](size_t f) { return convert ? ptOffset[f + 1] - ptOffset[f] : 0; };
  blockedWithProgress(nf, options.progress, 0.0, 0.5, [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) {
      FaceInfo& fi = info[f];
      if (fi.degenerate) continue;
      Vec3d n = faceNormal[f].cast<double>();
      double s0 = n.cross(planes.normal[0]).norm(), s1 = n.cross(planes.normal[1]).norm();
      bool first = s0 > 0 && (s0 >= double(options.familySwitchSine) || s0 >= s1);
      double s = first ? s0 : s1;
      fi.family = first ? 0 : 1;
      int m = 0;  // smallest m with 2^m sin θ >= 1 (tolerance: sin θ = 1 up to rounding keeps d)
      for (double scaled = s; m < 60 && scaled < 1 - 1e-12; scaled *= 2) ++m;
      // Faces almost parallel to the planes (only with familySwitchSine < 1) could need a level
      // beyond exact integers: cap it there (their cut count is bounded anyway).
      const auto& F = mesh.faces[f];
      const std::vector<double>& val = values[fi.family];
      const double vmax = std::max({std::abs(val[F[0]]), std::abs(val[F[1]]), std::abs(val[F[2]]), 1.0});
      while (m > 0 && vmax * double(uint64_t(1) << m) >= kExact) --m;
      fi.level = uint8_t(m);
      Cutter::Sorted sf = cutter.sorted(f, fi);
      fi.touch = sf.topTouch;
      segOffset[f + 1] = sf.cuts();
    }
  });
  // Every cut is at least one primitive: refuse an absurd spacing before cutting anything.
  size_t cuts = 0;
  for (size_t f = 0; f < nf; ++f) cuts += segOffset[f + 1];
  if (cuts > options.maxPrimitives)
    throwBadParameter("spacing", fmt::format("d = {:.6g} would cut {} segments (limit {}); use a larger spacing",
                                             d, cuts, options.maxPrimitives));
  if (convert) {
    parallelFor(0, nf, [&](size_t f) {
      FaceInfo& fi = info[f];
      if (fi.degenerate || segOffset[f + 1] == 0) return;
      size_t segs = 0, pts = 0;
      cutter.cut(f, fi, [&](const EdgePoint&, const EdgePoint&, const Vec3f& p0, const Vec3f& p1) {
        double l = (p1 - p0).cast<double>().norm();
        if (cutter.toPoints(l)) {
          pts += cutter.pointsFor(l);
          ++fi.converted;
        } else {
          ++segs;
        }
      });
      segOffset[f + 1] = segs;
      ptOffset[f + 1] = pts;
    }, 1024);
  }

  // Prefix sums: each face writes its own slots, so the output is the same for any thread count.
  for (size_t f = 0; f < nf; ++f) {
    segOffset[f + 1] += segOffset[f];
    if (convert) ptOffset[f + 1] += ptOffset[f];
    const FaceInfo& fi = info[f];
    if (fi.degenerate) continue;
    ++stats.cutByFamily[fi.family];
    stats.halvedSpacing += fi.level > 0;
    stats.vertexTouches += fi.touch;
    stats.convertedSegments += fi.converted;
    stats.uncutTriangles += segCount(f) + ptCount(f) == 0;
  }
  stats.segments = segOffset[nf];
  stats.points = convert ? ptOffset[nf] : 0;
  if (stats.segments + stats.points > options.maxPrimitives)
    throwBadParameter("spacing", fmt::format("d = {:.6g} would cut {} segments and {} points (limit {}); use a larger spacing",
                                             d, stats.segments, stats.points, options.maxPrimitives));

  const bool texcoords = mesh.cornerUVs.size() == nf && nf > 0;
  Interpolator interp{mesh, unitVertexNormals, texcoords && mesh.texture && !mesh.texture->empty(),
                      mesh.colors.size() == nv && nv > 0, texcoords};
  const float radius = float(stats.radius);
  model.segments.resize(stats.segments);
  model.points.resize(stats.points);
  if (shading) model.pointShadingNormals.resize(stats.points);
  float* masses = nullptr;
  if (options.pointMasses && stats.points > 0) {
    std::vector<float>& m = model.pointProperties[kPointMassProperty];
    m.assign(stats.points, 1.0f);
    masses = m.data();
  }
  if (options.recordFaces) {
    stats.segmentFaces.resize(stats.segments);
    stats.pointFaces.resize(stats.points);
  }

  // Polyline merging (docs/decisions.md "Polyline merging"): the ends' mesh edges and planes, and
  // the vertex normals there.
  const bool merge = options.mergeNormalDeviation > 0 && options.mergeMaxPieces > 1 && stats.segments > 1;
  std::vector<detail::ContourEndKey> endKeys(merge ? 2 * stats.segments : 0);
  std::vector<Vec3f> endNormals(merge && (useVertexNormals || smooth) ? 2 * stats.segments : 0);

  // Pass C: write the primitives.
  blockedWithProgress(nf, options.progress, 0.5, 1.0, [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) {
      const FaceInfo& fi = info[f];
      if (fi.degenerate || segCount(f) + ptCount(f) == 0) continue;
      size_t si = segOffset[f], pi = convert ? ptOffset[f] : 0;
      const Vec3f fn = faceNormal[f];
      cutter.cut(f, fi, [&](const EdgePoint& ea, const EdgePoint& eb, const Vec3f& p0, const Vec3f& p1) {
        double w0[3], w1[3];
        weightsOf(ea, w0);
        weightsOf(eb, w1);
        double l = (p1 - p0).cast<double>().norm();
        if (convert && cutter.toPoints(l)) {
          size_t n = cutter.pointsFor(l);
          for (size_t j = 0; j < n; ++j) {
            double tau = n > 1 ? double(j) / double(n - 1) : 0.5;
            double w[3] = {w0[0] + tau * (w1[0] - w0[0]), w0[1] + tau * (w1[1] - w0[1]), w0[2] + tau * (w1[2] - w0[2])};
            Point& p = model.points[pi];
            p.position = (p0.cast<double>() + tau * (p1 - p0).cast<double>()).cast<float>();
            p.normal = fn;
            if (useVertexNormals) {
              Vec3d vn = interp.vertexNormal(f, w);
              if (vn != Vec3d::Zero()) p.normal = vn.cast<float>();
            }
            if (smooth) {  // the shading normal the segment would have here (see below)
              Vec3d vn = interp.vertexNormal(f, w);
              if (l > 0) {
                const Vec3d dir = (p1 - p0).cast<double>() / l;
                vn -= vn.dot(dir) * dir;
              }
              if (vn.norm() > 1e-6) p.normal = limitTilt(vn.normalized(), fn.cast<double>()).cast<float>();
            }
            if (shading) {  // the full interpolated vertex normal lights the point
              const Vec3d vn = interp.vertexNormal(f, w);
              model.pointShadingNormals[pi] = vn != Vec3d::Zero() ? Vec3f(vn.cast<float>()) : p.normal;
            }
            p.color = interp.color(f, w);
            p.radius = radius;
            if (masses) {  // the length it stands for / radius (a segment's weight per length)
              const double spacing = n > 1 ? l / double(n - 1) : 0.0, share = j == 0 || j + 1 == n ? 0.5 : 1.0;
              masses[pi] = float(std::clamp(share * spacing / double(radius), kMinPointMass, double(kMaxPointMass)));
            }
            if (options.recordFaces) stats.pointFaces[pi] = uint32_t(f);
            ++pi;
          }
          return;
        }
        Segment& s = model.segments[si];
        s.p0 = p0;
        s.p1 = p1;
        s.normal = fn;
        double wm[3] = {0.5 * (w0[0] + w1[0]), 0.5 * (w0[1] + w1[1]), 0.5 * (w0[2] + w1[2])};
        if (useVertexNormals || smooth) {
          Vec3d vn = interp.vertexNormal(f, wm);
          Vec3d dir = (p1 - p0).cast<double>().normalized();
          vn -= vn.dot(dir) * dir;  // a segment's normal is perpendicular to it
          if (vn.norm() > 1e-6) s.normal = (smooth ? limitTilt(vn.normalized(), fn.cast<double>()) : Vec3d(vn.normalized())).cast<float>();
        }
        if (smooth) {  // interpolated vertex normals at the endpoints (perpendicular to the
                       // segment unless shading normals keep their component along it)
          const Vec3d dir = (p1 - p0).cast<double>().normalized();
          auto endNormal = [&](const double w[3]) {
            Vec3d vn = interp.vertexNormal(f, w);
            if (!shading) vn -= vn.dot(dir) * dir;
            return vn.norm() > 1e-6 ? Vec3f(vn.normalized().cast<float>()) : s.normal;
          };
          s.normal0 = endNormal(w0);
          s.normal1 = endNormal(w1);
        }
        s.color = interp.color(f, wm);
        s.radius = radius;
        if (texcoords) {
          s.uv0 = interp.uv(f, w0);
          s.uv1 = interp.uv(f, w1);
        }
        if (options.recordFaces) stats.segmentFaces[si] = uint32_t(f);
        if (merge) {
          const auto& F = mesh.faces[f];
          endKeys[2 * si] = detail::contourEndKey(F[ea.a], F[ea.b], ea.plane, fi.level, fi.family);
          endKeys[2 * si + 1] = detail::contourEndKey(F[eb.a], F[eb.b], eb.plane, fi.level, fi.family);
          if (!endNormals.empty()) {
            endNormals[2 * si] = interp.vertexNormal(f, w0).cast<float>();
            endNormals[2 * si + 1] = interp.vertexNormal(f, w1).cast<float>();
          }
        }
        ++si;
      });
    }
  });

  stats.segmentsBeforeMerge = stats.segments;
  if (merge) {
    detail::ContourMergeLimits lim;
    lim.normalDeviation = double(options.mergeNormalDeviation) * d;
    lim.tangentDeviation = double(options.mergeTangentDeviation) * d;
    lim.cosAngle = std::cos(double(options.mergeAngle) * std::numbers::pi / 180.0);
    // flat models: the strip normal is the shading normal, so mergeAngle bounds it
    lim.cosStripAngle = smooth ? std::cos(double(options.mergeStripAngle) * std::numbers::pi / 180.0) : lim.cosAngle;
    lim.maxPieces = options.mergeMaxPieces;
    if (interp.textured && mesh.texture->width > 0 && mesh.texture->height > 0)
      lim.uvTolerance = 0.5 / double(std::max(mesh.texture->width, mesh.texture->height));
    lim.colorTolerance = kMergeColorTolerance;
    lim.smooth = smooth;
    lim.alongNormals = shading;
    const detail::ContourMergeCounts c = detail::mergeContourPolylines(
        model.segments, endKeys, endNormals, lim, options.recordFaces ? &stats.segmentFaces : nullptr);
    stats.segments = model.segments.size();
    stats.polylines = c.polylines;
  }

  model.attributes.normals = true;
  model.attributes.radii = true;
  model.attributes.colors = interp.textured || interp.vertexColors;
  model.attributes.texcoords = texcoords && !model.segments.empty();
  model.attributes.endpointNormals = smooth && !model.segments.empty();
  model.attributes.shadingNormals = shading && !model.points.empty();
  if (!model.attributes.shadingNormals) model.pointShadingNormals.clear();
  if (texcoords) model.texture = mesh.texture;
  model.comments.push_back(fmt::format("linesurf extract contour (thesis §3.3): spacing d = {:.9g}, radius = {:.9g}, "
                                       "planes n0 = ({:.6f}, {:.6f}, {:.6f}), n1 = ({:.6f}, {:.6f}, {:.6f})",
                                       d, stats.radius, planes.normal[0].x(), planes.normal[0].y(), planes.normal[0].z(),
                                       planes.normal[1].x(), planes.normal[1].y(), planes.normal[1].z()));
  stats.seconds = timer.seconds();
  if (statsOut) *statsOut = std::move(stats);
  return model;
}

}  // namespace linesurf
