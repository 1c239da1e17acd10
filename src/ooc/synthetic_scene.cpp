// Synthetic open scenes with ground truth (see ooc/synthetic_scene.h).
#include "linesurf/ooc/synthetic_scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>

#include "linesurf/core/parallel.h"
#include "linesurf/ooc/point_stream.h"
#include "ooc/scan_hash.h"

namespace linesurf::ooc {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

using detail::splitmix;
using detail::unit;

/// Uniform deviates in [0, 1) from one hash, in a fixed order.
struct Draws {
  uint64_t s;
  double next() { return unit(s = splitmix(s)); }
  double in(double lo, double hi) { return lo + (hi - lo) * next(); }
};

/// The nearest hit so far along a ray o + t d (d unit): its parameter, the surface normal
/// turned towards the ray, the class.
struct Hit {
  double t = kInf;
  Vec3d n = Vec3d::Zero();
  uint8_t cls = kSceneGround;
  void take(double t2, const Vec3d& n2, uint8_t c) {
    if (t2 > 0 && t2 < t) t = t2, n = n2, cls = c;
  }
};

/// A convex solid as the intersection of half-spaces n.p <= c (n unit, pointing out), each
/// face with its class; a bounding sphere skips the rays that pass far away.
struct Convex {
  struct Face {
    Vec3d n;
    double c;
    uint8_t cls;
  };
  std::array<Face, 7> faces{};
  int count = 0;
  Vec3d centre = Vec3d::Zero();
  double radius = 0;
  void add(const Vec3d& n, double c, uint8_t cls) {
    const double l = n.norm();
    faces[size_t(count++)] = {n / l, c / l, cls};
  }
};

/// A box standing upright: centre (cx, cy), its own x axis at `angle` from the world's, half
/// widths hu, hv, from z0 to z1 (top face omitted when z1 is infinite, for gabled roofs).
Convex uprightBox(double cx, double cy, double angle, double hu, double hv, double z0, double z1, uint8_t side,
                  uint8_t top, uint8_t bottom) {
  Convex b;
  const Vec3d u(std::cos(angle), std::sin(angle), 0), v(-std::sin(angle), std::cos(angle), 0);
  const Vec3d c(cx, cy, 0);
  b.add(u, u.dot(c) + hu, side);
  b.add(-u, -u.dot(c) + hu, side);
  b.add(v, v.dot(c) + hv, side);
  b.add(-v, -v.dot(c) + hv, side);
  b.add(Vec3d(0, 0, -1), -z0, bottom);
  if (std::isfinite(z1)) b.add(Vec3d(0, 0, 1), z1, top);
  const double zt = std::isfinite(z1) ? z1 : z0;
  b.centre = Vec3d(cx, cy, 0.5 * (z0 + zt));
  b.radius = std::sqrt(hu * hu + hv * hv + 0.25 * (zt - z0) * (zt - z0));
  return b;
}

/// Enters `s` from outside along o + t d (Cyrus-Beck): the entry face, when nearer than hit.
void enter(const Convex& s, const Vec3d& o, const Vec3d& d, Hit& hit) {
  const Vec3d oc = s.centre - o;
  const double tc = oc.dot(d);
  if (oc.squaredNorm() - tc * tc > s.radius * s.radius) return;
  double t0 = -kInf, t1 = hit.t;
  int face = -1;
  for (int k = 0; k < s.count; ++k) {
    const Convex::Face& f = s.faces[size_t(k)];
    const double den = f.n.dot(d), num = f.c - f.n.dot(o);
    if (den == 0) {
      if (num < 0) return;  // parallel to the face, outside it
      continue;
    }
    const double t = num / den;
    if (den < 0) {
      if (t > t0) t0 = t, face = k;
    } else if (t < t1) {
      t1 = t;
    }
    if (t0 > t1) return;
  }
  if (face >= 0) hit.take(t0, s.faces[size_t(face)].n, s.faces[size_t(face)].cls);
}

/// Leaves the axis-aligned box [lo, hi] from o inside along d: the exit face with its normal
/// turned inward (towards o). cls: the classes of the faces -x +x -y +y -z +z.
void leave(const Vec3d& lo, const Vec3d& hi, const Vec3d& o, const Vec3d& d, const std::array<uint8_t, 6>& cls,
           Hit& hit) {
  double best = kInf;
  int axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) continue;
    const double t = ((d[a] > 0 ? hi[a] : lo[a]) - o[a]) / d[a];
    if (t < best) best = t, axis = a;
  }
  if (axis < 0) return;
  Vec3d n = Vec3d::Zero();
  n[axis] = d[axis] > 0 ? -1 : 1;
  hit.take(best, n, cls[size_t(2 * axis + (d[axis] > 0 ? 1 : 0))]);
}

/// A direction uniform over the sphere.
Vec3d sphereDirection(Draws& r) {
  const double z = 2 * r.next() - 1, phi = 2 * kPi * r.next();
  const double s = std::sqrt(std::max(0.0, 1 - z * z));
  return Vec3d(s * std::cos(phi), s * std::sin(phi), z);
}

// ---------------------------------------------------------------------------------------------
// Terrain

constexpr double kTerrainHalf = 100;     // the area [-100, 100]^2
constexpr double kFlightHeight = 500;    // the flight line x = 0, z = 500
constexpr double kMaxTilt = 20 * kPi / 180;
constexpr double kCrownMeanFreePath = 2;  // mean depth of a return inside a crown, m

struct GroundWave {
  double kx, ky, amp, phase;
};

struct Crown {
  Vec3d centre;
  double rh, rz;  // horizontal and vertical semi-axes
};

struct TerrainLayout {
  std::array<GroundWave, 3> waves{};
  std::vector<Convex> buildings;
  std::vector<Crown> crowns;

  double ground(double x, double y, double* gx = nullptr, double* gy = nullptr) const {
    double h = 0, dx = 0, dy = 0;
    for (const GroundWave& w : waves) {
      const double a = w.kx * x + w.ky * y + w.phase;
      h += w.amp * std::sin(a);
      const double c = w.amp * std::cos(a);
      dx += c * w.kx, dy += c * w.ky;
    }
    if (gx) *gx = dx, *gy = dy;
    return h;
  }
  /// The highest ground over a square of half width r around (x, y), on a 9 x 9 grid: what a
  /// building or crown must clear.
  double highestGround(double x, double y, double r) const {
    double m = -kInf;
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; j <= 8; ++j) m = std::max(m, ground(x + r * (i / 4.0 - 1), y + r * (j / 4.0 - 1)));
    return m;
  }
};

/// The terrain's geometry: fixed (its own seed), so the same scene for every sampling seed.
const TerrainLayout& terrainLayout() {
  static const TerrainLayout layout = [] {
    TerrainLayout L;
    // Wavelength, amplitude, direction, phase: the gradients sum to at most
    // 2 pi (3/150 + 1.5/80 + 0.5/30) = 0.348, a slope of 19.2 degrees; heights within +-5 m.
    const double spec[3][4] = {{150, 3.0, 0.4, 0.3}, {80, 1.5, 2.1, 1.7}, {30, 0.5, 3.9, 4.4}};
    for (int k = 0; k < 3; ++k) {
      const double kk = 2 * kPi / spec[k][0];
      L.waves[size_t(k)] = {kk * std::cos(spec[k][2]), kk * std::sin(spec[k][2]), spec[k][1], spec[k][3]};
    }
    Draws r{0x7e55a1a7e5ull};
    struct Foot {
      double x, y, r;
    };
    std::vector<Foot> feet;
    while (L.buildings.size() < 12) {
      const bool gabled = L.buildings.size() % 2 == 1;
      const double wu = r.in(8, 30), wv = gabled ? r.in(8, 16) : r.in(8, 30);  // gables span v
      const double angle = r.in(0, kPi / 2), x = r.in(-82, 82), y = r.in(-82, 82);
      const double rad = 0.5 * std::hypot(wu, wv);
      bool free = std::max(std::abs(x), std::abs(y)) + rad < 95;
      for (const Foot& f : feet) free = free && std::hypot(x - f.x, y - f.y) > rad + f.r + 4;
      if (!free) continue;
      feet.push_back({x, y, rad});
      // Heights above the highest ground under the footprint, so that no slope pierces a roof;
      // the walls go down to z = -30, below all ground, so the ground under a building is
      // never seen.
      const double base = L.highestGround(x, y, rad);
      if (!gabled) {
        L.buildings.push_back(uprightBox(x, y, angle, wu / 2, wv / 2, -30, base + r.in(4, 20), kSceneWall, kSceneRoof,
                                         kSceneGround));
        continue;
      }
      const double eave = base + r.in(4, 12), pitch = r.in(25, 40) * kPi / 180;
      const double s = std::tan(pitch), hv = wv / 2;
      Convex b = uprightBox(x, y, angle, wu / 2, hv, -30, kInf, kSceneWall, kSceneRoof, kSceneGround);
      // The two roof planes z + s v.(p - c) <= eave + s hv and z - s v.(p - c) <= eave + s hv,
      // meeting at the ridge above the axis u; the gable ends are the walls +-u up to them.
      const Vec3d v(-std::sin(angle), std::cos(angle), 0), c(x, y, 0);
      const double ridge = eave + s * hv;
      for (const double sign : {1.0, -1.0}) {
        const Vec3d n = sign * s * v + Vec3d(0, 0, 1);
        b.add(n, ridge + sign * s * v.dot(c), kSceneRoof);
      }
      b.centre = Vec3d(x, y, 0.5 * (-30 + ridge));
      b.radius = std::sqrt(rad * rad + 0.25 * (ridge + 30) * (ridge + 30));
      L.buildings.push_back(b);
    }
    while (L.crowns.size() < 40) {
      const double rh = r.in(2.5, 6), rz = rh * r.in(0.8, 1.3), trunk = r.in(1.5, 4);
      const double x = r.in(-92, 92), y = r.in(-92, 92);
      bool free = true;
      for (const Foot& f : feet) free = free && std::hypot(x - f.x, y - f.y) > f.r + rh + 2;
      for (const Crown& c : L.crowns) free = free && std::hypot(x - c.centre.x(), y - c.centre.y()) > rh + c.rh + 0.5;
      if (!free) continue;
      L.crowns.push_back({Vec3d(x, y, L.highestGround(x, y, rh) + trunk + rz), rh, rz});
    }
    return L;
  }();
  return layout;
}

/// The ground's first hit. Along a ray within 20 degrees of nadir over slopes under 20 degrees,
/// z(t) - ground(t) falls strictly (its derivative lies in [-1.07, -0.82]), so Newton's method
/// from the hit on z = 0 contracts to the one root.
void groundHit(const TerrainLayout& L, const Vec3d& o, const Vec3d& d, Hit& hit) {
  double t = -o.z() / d.z();
  for (int it = 0; it < 60; ++it) {
    double gx, gy;
    const Vec3d p = o + t * d;
    const double f = p.z() - L.ground(p.x(), p.y(), &gx, &gy);
    const double step = f / (d.z() - gx * d.x() - gy * d.y());
    t -= step;
    if (std::abs(step) < 1e-10) break;
  }
  double gx, gy;
  const Vec3d p = o + t * d;
  L.ground(p.x(), p.y(), &gx, &gy);
  hit.take(t, Vec3d(-gx, -gy, 1).normalized(), kSceneGround);
}

/// The crowns a pulse passes before `hit`: at each, in the order met, a return at an
/// exponentially distributed depth if it falls inside the chord, with the normal pointing back
/// along the ray.
void crownHits(const TerrainLayout& L, const Vec3d& o, const Vec3d& d, Draws& r, Hit& hit) {
  std::array<std::pair<double, double>, 40> chords;  // entry, exit
  size_t m = 0;
  for (const Crown& c : L.crowns) {
    // The ellipsoid scaled to the unit sphere.
    const Vec3d s(1 / c.rh, 1 / c.rh, 1 / c.rz);
    const Vec3d oc = (o - c.centre).cwiseProduct(s), ds = d.cwiseProduct(s);
    const double a = ds.squaredNorm(), b = oc.dot(ds), cc = oc.squaredNorm() - 1;
    const double disc = b * b - a * cc;
    if (disc <= 0) continue;
    const double q = std::sqrt(disc);
    const double t0 = (-b - q) / a, t1 = (-b + q) / a;
    if (t0 < hit.t && t1 > 0 && m < chords.size()) chords[m++] = {std::max(t0, 0.0), t1};
  }
  std::sort(chords.begin(), chords.begin() + std::ptrdiff_t(m));
  for (size_t k = 0; k < m; ++k) {
    const double depth = -kCrownMeanFreePath * std::log(1 - r.next());
    const double t = chords[k].first + depth;
    if (t < std::min(chords[k].second, hit.t)) {
      hit.take(t, -d, kSceneVegetation);
      return;
    }
  }
}

/// One pulse of the flight: a target on z = 0 uniform over the area, and the sensor position
/// on the line x = 0, z = 500 uniform among those seeing the target within 20 degrees.
bool terrainRay(Draws& r, Vec3d& o, Vec3d& d, Hit& hit) {
  const TerrainLayout& L = terrainLayout();
  const double qx = r.in(-kTerrainHalf, kTerrainHalf), qy = r.in(-kTerrainHalf, kTerrainHalf);
  const double reach = kFlightHeight * std::tan(kMaxTilt);
  const double w = std::sqrt(reach * reach - qx * qx);
  o = Vec3d(0, qy + w * (2 * r.next() - 1), kFlightHeight);
  d = (Vec3d(qx, qy, 0) - o).normalized();
  groundHit(L, o, d, hit);
  for (const Convex& b : L.buildings) enter(b, o, d, hit);
  crownHits(L, o, d, r, hit);
  const Vec3d p = o + hit.t * d;
  return std::abs(p.x()) <= kTerrainHalf && std::abs(p.y()) <= kTerrainHalf;
}

// ---------------------------------------------------------------------------------------------
// Room

const Vec3d kRoomLo(-4, -3, 0), kRoomHi(4, 3, 3);
const Vec3d kRoomScanner(0.8, -0.6, 1.5);

const std::vector<Convex>& roomObjects() {
  static const std::vector<Convex> objects = {
      uprightBox(-1.8, 1.0, 20 * kPi / 180, 0.8, 0.45, 0, 0.75, kSceneObject, kSceneObject, kSceneObject),  // table
      uprightBox(2.9, -1.9, -10 * kPi / 180, 0.3, 0.6, 0, 2.0, kSceneObject, kSceneObject, kSceneObject),   // cabinet
      uprightBox(-0.4, -2.0, 35 * kPi / 180, 0.25, 0.25, 0, 0.5, kSceneObject, kSceneObject, kSceneObject),  // crate
  };
  return objects;
}

bool roomRay(Draws& r, Vec3d& o, Vec3d& d, Hit& hit) {
  o = kRoomScanner;
  d = sphereDirection(r);
  leave(kRoomLo, kRoomHi, o, d, {kSceneWall, kSceneWall, kSceneWall, kSceneWall, kSceneGround, kSceneRoof}, hit);
  for (const Convex& b : roomObjects()) enter(b, o, d, hit);
  return std::isfinite(hit.t);
}

// ---------------------------------------------------------------------------------------------
// Facade

constexpr double kFacadeHalf = 30, kFacadeTop = 15, kStreetDepth = 15;
constexpr double kSensorY = -10, kSensorZ = 2.5, kFacadeCone = 70 * kPi / 180;
constexpr double kBay = 3, kStorey = 3.6, kRecess = 0.2;  // 20 bays, 4 storeys
constexpr double kWindowHalf = 0.7, kSill = 0.9, kLintel = 2.5;  // window in its bay and storey
constexpr double kBalconyDepth = 1.4;

const std::vector<Convex>& balconies() {
  static const std::vector<Convex> parts = [] {
    std::vector<Convex> v;
    const int spec[5][3] = {{1, 2, 3}, {2, 2, 3}, {3, 2, 3}, {1, 10, 11}, {2, 15, 16}};  // storey, bays
    for (const auto& b : spec) {
      const double x0 = -kFacadeHalf + kBay * b[1] + 0.2, x1 = -kFacadeHalf + kBay * (b[2] + 1) - 0.2;
      const double zf = kStorey * b[0], cx = 0.5 * (x0 + x1), hx = 0.5 * (x1 - x0);
      // The slab (its top the storey's floor) and the balustrade panel at its front edge.
      v.push_back(uprightBox(cx, -kBalconyDepth / 2, 0, hx, kBalconyDepth / 2, zf - 0.2, zf, kSceneObject, kSceneObject,
                             kSceneObject));
      v.push_back(uprightBox(cx, -kBalconyDepth + 0.03, 0, hx, 0.03, zf, zf + 1.0, kSceneObject, kSceneObject,
                             kSceneObject));
    }
    return v;
  }();
  return parts;
}

bool facadeRay(Draws& r, Vec3d& o, Vec3d& d, Hit& hit) {
  o = Vec3d(r.in(-kFacadeHalf, kFacadeHalf), kSensorY, kSensorZ);
  // Uniform over the cone's solid angle around +y.
  const double ca = 1 - r.next() * (1 - std::cos(kFacadeCone)), sa = std::sqrt(std::max(0.0, 1 - ca * ca));
  const double b = 2 * kPi * r.next();
  d = Vec3d(sa * std::cos(b), ca, sa * std::sin(b));
  if (d.z() < 0) {  // the street
    const double t = -o.z() / d.z();
    const Vec3d p = o + t * d;
    if (std::abs(p.x()) <= kFacadeHalf && p.y() <= 0 && p.y() >= -kStreetDepth)
      hit.take(t, Vec3d(0, 0, 1), kSceneGround);
  }
  const double tf = -o.y() / d.y();  // the facade plane y = 0 (d.y() >= cos 70 degrees)
  const Vec3d p = o + tf * d;
  if (std::abs(p.x()) <= kFacadeHalf && p.z() >= 0 && p.z() <= kFacadeTop) {
    const double bay = std::floor((p.x() + kFacadeHalf) / kBay), storey = std::floor(p.z() / kStorey);
    const double xc = -kFacadeHalf + kBay * (bay + 0.5), zf = kStorey * storey;
    const Vec3d lo(xc - kWindowHalf, 0, zf + kSill), hi(xc + kWindowHalf, kRecess, zf + kLintel);
    if (p.x() > lo.x() && p.x() < hi.x() && p.z() > lo.z() && p.z() < hi.z()) {
      // Into the recess: the glass, a reveal, the sill or the lintel, seen from inside the box.
      Hit in;
      leave(lo, hi, p, d, {kSceneWall, kSceneWall, kSceneWall, kSceneWall, kSceneWall, kSceneWall}, in);
      hit.take(tf + in.t, in.n, in.cls);
    } else {
      hit.take(tf, Vec3d(0, -1, 0), kSceneWall);
    }
  }
  for (const Convex& c : balconies()) enter(c, o, d, hit);
  return std::isfinite(hit.t);
}

}  // namespace

const char* sceneName(SceneKind kind) {
  switch (kind) {
    case SceneKind::Terrain: return "terrain";
    case SceneKind::Room: return "room";
    case SceneKind::Facade: return "facade";
  }
  return "?";
}

double sceneSpacing(const SyntheticSceneOptions& o) {
  const double area = o.kind == SceneKind::Terrain ? 4 * kTerrainHalf * kTerrainHalf
                      : o.kind == SceneKind::Room  ? 2 * (8.0 * 6 + 8.0 * 3 + 6.0 * 3)
                                                   : 2 * kFacadeHalf * (kFacadeTop - kSensorY);
  return std::sqrt(area / double(std::max<uint64_t>(o.count, 1)));
}

Vec3d sceneSensor(const SyntheticSceneOptions& o) {
  switch (o.kind) {
    case SceneKind::Terrain: return Vec3d(0, 0, kFlightHeight);
    case SceneKind::Room: return kRoomScanner;
    case SceneKind::Facade: return Vec3d(0, kSensorY, kSensorZ);
  }
  return Vec3d::Zero();
}

void syntheticScenePoints(const SyntheticSceneOptions& o, uint64_t first, size_t n, std::vector<ScenePoint>& out) {
  if (o.kind == SceneKind::Terrain) terrainLayout();  // built once, before the workers need it
  const double sigma = o.noise * sceneSpacing(o);
  bool (*const ray)(Draws&, Vec3d&, Vec3d&, Hit&) =
      o.kind == SceneKind::Terrain ? terrainRay : o.kind == SceneKind::Room ? roomRay : facadeRay;
  out.resize(n);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) {
      const uint64_t h = splitmix(o.seed * 0x9e3779b97f4a7c15ull + first + k);
      Vec3d org, d;
      Hit hit;
      // A ray that leaves the scene is drawn again; every scene hits on most first attempts.
      for (uint64_t attempt = 0;; ++attempt) {
        if (attempt == 100000) throw std::logic_error("synthetic scene: no ray hits the scene");
        Draws r{splitmix(h + (attempt + 1) * 0xd1b54a32d192ed03ull)};
        hit = Hit();
        if (ray(r, org, d, hit)) break;
      }
      // Box-Muller normal deviate for the noise along the true normal, from its own hash so
      // that the noise-free and the noisy scene share every ray.
      Draws g{splitmix(h ^ 0x6e6f697365ull)};
      const double u1 = g.next(), u2 = g.next();
      const double dev = std::sqrt(-2 * std::log(1 - u1)) * std::cos(2 * kPi * u2);
      ScenePoint& p = out[k];
      p.position = (org + hit.t * d + sigma * dev * hit.n).cast<float>();
      p.normal = hit.n.cast<float>();
      p.cls = hit.cls;
    }
  }, 1024);
}

void writeSyntheticScene(const std::filesystem::path& path, const SyntheticSceneOptions& o,
                         const std::filesystem::path& truth) {
  char noise[32];
  std::snprintf(noise, sizeof noise, "%g", o.noise);
  const std::string what = std::string("linesurf synthetic scene: ") + sceneName(o.kind) + " count " +
                           std::to_string(o.count) + " seed " + std::to_string(o.seed) + " noise " + noise;
  PlyPointWriter writer(path, o.count, {what}, false, false);
  std::unique_ptr<PlyPointWriter> truthWriter;
  if (!truth.empty())
    truthWriter = std::make_unique<PlyPointWriter>(
        truth, o.count,
        std::vector<std::string>{what, "truth: true normals facing the scanner's side; class 0 ground 1 roof 2 wall "
                                       "3 vegetation 4 object"},
        true, false, "", std::vector<std::string>{"class"});
  std::vector<ScenePoint> pts;
  std::vector<Vec3f> pos, nrm;
  std::vector<float> cls;
  const uint64_t chunk = 1 << 20;
  for (uint64_t b = 0; b < o.count; b += chunk) {
    const size_t n = size_t(std::min(chunk, o.count - b));
    syntheticScenePoints(o, b, n, pts);
    pos.resize(n), nrm.resize(n), cls.resize(n);
    for (size_t k = 0; k < n; ++k) pos[k] = pts[k].position, nrm[k] = pts[k].normal, cls[k] = float(pts[k].cls);
    writer.write(pos.data(), nullptr, nullptr, n);
    if (truthWriter) truthWriter->write(pos.data(), nrm.data(), nullptr, n, cls.data());
  }
  writer.finish();
  if (truthWriter) truthWriter->finish();
}

}  // namespace linesurf::ooc
