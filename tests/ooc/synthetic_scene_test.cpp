// Synthetic open scenes (ooc/synthetic_scene.h): deterministic in chunks and threads, points on
// their analytic surfaces with unit true normals facing the scanner, plausible class shares,
// noise along the normal, and the files they are written to.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <numbers>
#include <sstream>

#include "linesurf/core/parallel.h"
#include "linesurf/ooc/point_stream.h"
#include "linesurf/ooc/synthetic_scene.h"
#include "test_util.h"

namespace linesurf {
namespace {

using ooc::SceneKind;
using ooc::ScenePoint;
using ooc::SyntheticSceneOptions;

constexpr std::array<SceneKind, 3> kKinds = {SceneKind::Terrain, SceneKind::Room, SceneKind::Facade};

std::vector<ScenePoint> scene(SceneKind kind, uint64_t count, double noise = 0, uint64_t seed = 3) {
  SyntheticSceneOptions o;
  o.kind = kind, o.count = count, o.noise = noise, o.seed = seed;
  std::vector<ScenePoint> pts;
  ooc::syntheticScenePoints(o, 0, count, pts);
  return pts;
}

using OnSurface = std::function<bool(const Vec3d& x, const Vec3d& n, uint8_t cls)>;

/// The points' checks every scene shares: `on` holds for each point (its class's analytic
/// surface and normal), the normals are unit, and each class has at least its share.
void expectScene(const std::vector<ScenePoint>& pts, const OnSurface& on, const std::array<double, 5>& minShare) {
  size_t off = 0, notUnit = 0;
  std::array<double, 5> share{};
  for (const ScenePoint& p : pts) {
    const Vec3d x = p.position.cast<double>(), n = p.normal.cast<double>();
    off += !(p.cls < 5 && on(x, n, p.cls));
    notUnit += !(std::abs(n.norm() - 1) < 1e-6);
    if (p.cls < 5) share[p.cls] += 1.0 / double(pts.size());
  }
  EXPECT_EQ(off, 0u);
  EXPECT_EQ(notUnit, 0u);
  for (size_t c = 0; c < 5; ++c) EXPECT_GE(share[c], minShare[c]) << "class " << c;
}

bool same(const ScenePoint& a, const ScenePoint& b) {
  return a.position == b.position && a.normal == b.normal && a.cls == b.cls;
}

bool near(double a, double b, double tol = 1e-4) { return std::abs(a - b) < tol; }

TEST(SyntheticScene, ChunksAndThreadsGiveTheSamePoints) {
  for (SceneKind kind : kKinds) {
    SCOPED_TRACE(ooc::sceneName(kind));
    SyntheticSceneOptions o;
    o.kind = kind, o.count = 8000, o.seed = 11;
    std::vector<ScenePoint> whole;
    {
      ThreadLimit one(1);
      ooc::syntheticScenePoints(o, 0, o.count, whole);
    }
    ASSERT_EQ(whole.size(), o.count);
    ThreadLimit four(4);
    std::vector<ScenePoint> part;
    size_t differ = 0;
    for (const auto& [first, n] : {std::pair<uint64_t, size_t>{0, 2999}, {2999, 1}, {3000, 5000}}) {
      ooc::syntheticScenePoints(o, first, n, part);
      ASSERT_EQ(part.size(), n);
      for (size_t k = 0; k < n; ++k) differ += !same(part[k], whole[first + k]);
    }
    EXPECT_EQ(differ, 0u);
    // Another seed, other rays.
    o.seed = 12;
    ooc::syntheticScenePoints(o, 0, 100, part);
    size_t equal = 0;
    for (size_t k = 0; k < 100; ++k) equal += part[k].position == whole[k].position;
    EXPECT_EQ(equal, 0u);
  }
}

TEST(SyntheticScene, RoomPointsLieOnTheirPlanesAndFaceTheScanner) {
  SyntheticSceneOptions o;
  o.kind = SceneKind::Room;
  const Vec3d s = ooc::sceneSensor(o);
  EXPECT_EQ(s, Vec3d(0.8, -0.6, 1.5));
  const auto pts = scene(SceneKind::Room, 20000);
  size_t away = 0;
  for (const ScenePoint& p : pts) away += !(p.normal.cast<double>().dot(s - p.position.cast<double>()) > 0);
  EXPECT_EQ(away, 0u);
  expectScene(pts, [](const Vec3d& x, const Vec3d& n, uint8_t cls) {
    switch (cls) {
      case ooc::kSceneGround: return near(x.z(), 0) && n == Vec3d(0, 0, 1);
      case ooc::kSceneRoof: return near(x.z(), 3) && n == Vec3d(0, 0, -1);
      case ooc::kSceneWall:
        return (near(std::abs(x.x()), 4) && n == Vec3d(-std::copysign(1.0, x.x()), 0, 0)) ||
               (near(std::abs(x.y()), 3) && n == Vec3d(0, -std::copysign(1.0, x.y()), 0));
      case ooc::kSceneObject:
        // The free-standing boxes: clear of the walls, their faces vertical or their tops at
        // the table's, the cabinet's or the crate's height.
        return std::abs(x.x()) < 3.7 && std::abs(x.y()) < 2.7 &&
               near(std::abs(n.z()) + std::hypot(n.x(), n.y()), 1, 1e-6) &&
               (near(n.z(), 0, 1e-6) || near(x.z(), 0.75) || near(x.z(), 2.0) || near(x.z(), 0.5));
      default: return false;
    }
  }, {0.15, 0.15, 0.2, 0, 0.02});
}

TEST(SyntheticScene, FacadePointsLieOnTheFacadeRecessesBalconiesOrStreet) {
  SyntheticSceneOptions o;
  o.kind = SceneKind::Facade;
  EXPECT_LT(ooc::sceneSensor(o).y(), 0);  // the street side
  const auto pts = scene(SceneKind::Facade, 20000);
  size_t recess = 0;
  for (const ScenePoint& p : pts) recess += p.cls == ooc::kSceneWall && p.position.y() > 1e-4f;
  EXPECT_GT(recess, 100u);
  expectScene(pts, [](const Vec3d& x, const Vec3d& n, uint8_t cls) {
    auto frac = [](double v, double period) { return v - period * std::floor(v / period); };
    const bool inX = std::abs(x.x()) <= 30 + 1e-4;
    switch (cls) {
      case ooc::kSceneGround: return inX && near(x.z(), 0) && x.y() <= 1e-4 && x.y() >= -15 && n == Vec3d(0, 0, 1);
      case ooc::kSceneWall:
        // The facade y = 0, or in a window recess: the glass y = 0.2, a reveal 0.8 or 2.2 m into
        // its 3 m bay, a sill or lintel 0.9 or 2.5 m above its storey's floor.
        return inX && x.z() >= -1e-4 && x.z() <= 15 + 1e-4 &&
               ((near(x.y(), 0) && n == Vec3d(0, -1, 0)) || (near(x.y(), 0.2) && n == Vec3d(0, -1, 0)) ||
                (x.y() > -1e-4 && x.y() < 0.2 + 1e-4 &&
                 ((std::abs(n.x()) == 1 && (near(frac(x.x() + 30, 3), 0.8) || near(frac(x.x() + 30, 3), 2.2))) ||
                  (std::abs(n.z()) == 1 && (near(frac(x.z(), 3.6), 0.9) || near(frac(x.z(), 3.6), 2.5))))));
      case ooc::kSceneObject:  // the balconies
        return inX && x.y() >= -1.4 - 1e-4 && x.y() <= 1e-4 && x.z() > 3 &&
               (std::abs(n.x()) == 1 || std::abs(n.y()) == 1 || std::abs(n.z()) == 1);
      default: return false;
    }
  }, {0.2, 0, 0.3, 0, 0.01});
}

/// Clusters of points on one plane: the (normal, offset) pairs met, within tolerances.
size_t planes(const std::vector<ScenePoint>& pts, uint8_t cls, bool (*keep)(const Vec3d&)) {
  std::vector<std::pair<Vec3d, double>> seen;
  for (const ScenePoint& p : pts) {
    const Vec3d n = p.normal.cast<double>();
    if (p.cls != cls || !keep(n)) continue;
    const double c = n.dot(p.position.cast<double>());
    bool found = false;
    for (const auto& [m, d] : seen) found = found || ((m - n).norm() < 1e-5 && std::abs(d - c) < 1e-3);
    if (!found) seen.push_back({n, c});
  }
  return seen.size();
}

TEST(SyntheticScene, TerrainClassesNormalsAndPlanes) {
  SyntheticSceneOptions o;
  EXPECT_EQ(ooc::sceneSensor(o), Vec3d(0, 0, 500));
  const auto pts = scene(SceneKind::Terrain, 20000);
  expectScene(pts, [](const Vec3d& x, const Vec3d& n, uint8_t cls) {
    const double cos20 = std::cos(20 * std::numbers::pi / 180), cos25 = std::cos(25 * std::numbers::pi / 180),
                 cos40 = std::cos(40 * std::numbers::pi / 180);
    if (!(std::abs(x.x()) <= 100 && std::abs(x.y()) <= 100 && x.z() > -5.01 && x.z() < 25)) return false;
    switch (cls) {
      case ooc::kSceneGround: return n.z() > cos20 - 1e-6;  // slopes under 20 degrees
      case ooc::kSceneRoof: return n.z() == 1 || (n.z() > cos40 - 1e-6 && n.z() < cos25 + 1e-6);
      case ooc::kSceneWall: return n.z() == 0;
      case ooc::kSceneVegetation: return n.z() > cos20 - 1e-6;  // back towards the aircraft
      default: return false;
    }
  }, {0.4, 0.05, 0.005, 0.02, 0});
  // Noise-free roofs and walls lie on a few planes: 6 flat roofs, 6 gabled ones of two planes
  // each, and 4 walls a building (at most 48; a wall facing away from the whole flight line
  // gets no point).
  const size_t flat = planes(pts, ooc::kSceneRoof, [](const Vec3d& n) { return n.z() == 1; });
  const size_t sloped = planes(pts, ooc::kSceneRoof, [](const Vec3d& n) { return n.z() < 1; });
  const size_t walls = planes(pts, ooc::kSceneWall, [](const Vec3d&) { return true; });
  EXPECT_EQ(flat, 6u);
  EXPECT_EQ(sloped, 12u);
  EXPECT_GE(walls, 30u);
  EXPECT_LE(walls, 48u);
}

TEST(SyntheticScene, NoiseMovesEachPointAlongItsTrueNormal) {
  for (SceneKind kind : kKinds) {
    SCOPED_TRACE(ooc::sceneName(kind));
    SyntheticSceneOptions o;
    o.kind = kind, o.count = 5000;
    const auto clean = scene(kind, o.count, 0), noisy = scene(kind, o.count, 0.5);
    const double sigma = 0.5 * ooc::sceneSpacing(o);
    double sum2 = 0;
    size_t across = 0;
    for (size_t k = 0; k < clean.size(); ++k) {
      ASSERT_EQ(clean[k].cls, noisy[k].cls);
      ASSERT_EQ(clean[k].normal, noisy[k].normal);
      const Vec3d d = (noisy[k].position - clean[k].position).cast<double>();
      const double along = d.dot(clean[k].normal.cast<double>());
      across += (d - along * clean[k].normal.cast<double>()).norm() > 1e-4;
      sum2 += along * along;
    }
    EXPECT_EQ(across, 0u);
    const double rms = std::sqrt(sum2 / double(clean.size()));
    EXPECT_GT(rms, 0.9 * sigma);
    EXPECT_LT(rms, 1.1 * sigma);
  }
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(SyntheticScene, WritesThePointsAndTheTruth) {
  const auto dir = test::scratchDir("synthetic_scene");
  SyntheticSceneOptions o;
  o.kind = SceneKind::Facade, o.count = 3001, o.seed = 4;
  ooc::writeSyntheticScene(dir / "scene.ply", o, dir / "truth.ply");
  std::vector<ScenePoint> want;
  ooc::syntheticScenePoints(o, 0, o.count, want);

  ooc::PointReader r(dir / "scene.ply");
  EXPECT_EQ(r.info().count, o.count);
  EXPECT_FALSE(r.info().normals);
  std::vector<Vec3f> pos, nrm;
  ASSERT_EQ(r.read(pos, nrm, o.count + 10), o.count);
  for (size_t k = 0; k < o.count; ++k) ASSERT_EQ(pos[k], want[k].position) << k;

  // The truth: x y z nx ny nz class, floats.
  const std::string t = slurp(dir / "truth.ply");
  const size_t body = t.find("end_header\n");
  ASSERT_NE(body, std::string::npos);
  const std::string header = t.substr(0, body);
  EXPECT_NE(header.find("element vertex 3001\n"), std::string::npos);
  EXPECT_NE(header.find("property float nz\nproperty float class\n"), std::string::npos);
  ASSERT_EQ(t.size() - body - 11, o.count * 7 * 4);
  std::array<size_t, 5> counts{};
  for (size_t k = 0; k < o.count; ++k) {
    float row[7];
    std::memcpy(row, t.data() + body + 11 + k * 28, 28);
    ASSERT_EQ(Vec3f(row[0], row[1], row[2]), want[k].position) << k;
    ASSERT_EQ(Vec3f(row[3], row[4], row[5]), want[k].normal) << k;
    ASSERT_EQ(row[6], float(want[k].cls)) << k;
    ++counts[size_t(row[6])];
  }
  EXPECT_EQ(counts[0] + counts[2] + counts[4], o.count);

  // Without a truth path, only the points.
  ooc::writeSyntheticScene(dir / "alone.ply", o);
  EXPECT_EQ(slurp(dir / "alone.ply"), slurp(dir / "scene.ply"));
  size_t files = 0;  // and no temporary left beside them
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 3u);
}

}  // namespace
}  // namespace linesurf
