#include "shapes.h"

#include <cmath>
#include <map>
#include <numbers>
#include <random>

namespace linesurf::shapes {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

Point makePoint(const Vec3f& p, const Vec3f& n, float radius, const SampleOptions& o) {
  Point pt;
  pt.position = p;
  pt.normal = n.normalized();
  pt.color = o.color;
  pt.radius = radius;
  return pt;
}

HybridModel finish(std::vector<Point> pts) {
  HybridModel m;
  m.points = std::move(pts);
  m.attributes.normals = true;
  m.attributes.colors = true;
  m.attributes.radii = true;
  return m;
}

/// Adds isotropic Gaussian noise of standard deviation sigma to every position.
void addNoise(std::vector<Point>& pts, float sigma, std::mt19937_64& rng) {
  if (sigma <= 0) return;
  std::normal_distribution<float> g(0.0f, sigma);
  for (Point& p : pts) p.position += Vec3f(g(rng), g(rng), g(rng));
}

}  // namespace

HybridModel plane(float width, float height, int nx, int ny, const SampleOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float sx = width / std::max(nx - 1, 1), sy = height / std::max(ny - 1, 1);
  const float spacing = std::max(sx, sy);
  std::vector<Point> pts;
  pts.reserve(size_t(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      float x = o.irregular ? u(rng) : float(i) / std::max(nx - 1, 1);
      float y = o.irregular ? u(rng) : float(j) / std::max(ny - 1, 1);
      pts.push_back(makePoint(Vec3f((x - 0.5f) * width, (y - 0.5f) * height, 0), Vec3f(0, 0, 1), spacing, o));
    }
  addNoise(pts, o.noise * spacing, rng);
  return finish(std::move(pts));
}

HybridModel sphere(float r, int n, const SampleOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float spacing = r * std::sqrt(4 * kPi / std::max(n, 1));
  std::vector<Point> pts;
  pts.reserve(n);
  const float golden = kPi * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    float z, phi;
    if (o.irregular) {
      z = 2 * u(rng) - 1;
      phi = 2 * kPi * u(rng);
    } else {
      z = 1 - (2 * (i + 0.5f)) / n;
      phi = golden * i;
    }
    float s = std::sqrt(std::max(0.0f, 1 - z * z));
    Vec3f d(s * std::cos(phi), s * std::sin(phi), z);
    pts.push_back(makePoint(r * d, d, spacing, o));
  }
  addNoise(pts, o.noise * spacing, rng);
  return finish(std::move(pts));
}

HybridModel cylinder(float r, float h, int nAround, int nAlong, const SampleOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float spacing = std::max(2 * kPi * r / nAround, h / std::max(nAlong - 1, 1));
  std::vector<Point> pts;
  pts.reserve(size_t(nAround) * nAlong);
  for (int j = 0; j < nAlong; ++j)
    for (int i = 0; i < nAround; ++i) {
      float a = o.irregular ? 2 * kPi * u(rng) : 2 * kPi * i / nAround;
      float t = o.irregular ? u(rng) : float(j) / std::max(nAlong - 1, 1);
      Vec3f n(std::cos(a), std::sin(a), 0);
      pts.push_back(makePoint(Vec3f(r * n.x(), r * n.y(), (t - 0.5f) * h), n, spacing, o));
    }
  addNoise(pts, o.noise * spacing, rng);
  return finish(std::move(pts));
}

HybridModel torus(float R, float r, int nMajor, int nMinor, const SampleOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float spacing = std::max(2 * kPi * (R + r) / nMajor, 2 * kPi * r / nMinor);
  std::vector<Point> pts;
  pts.reserve(size_t(nMajor) * nMinor);
  for (int j = 0; j < nMinor; ++j)
    for (int i = 0; i < nMajor; ++i) {
      float a = o.irregular ? 2 * kPi * u(rng) : 2 * kPi * i / nMajor;
      float b = o.irregular ? 2 * kPi * u(rng) : 2 * kPi * j / nMinor;
      Vec3f c(R * std::cos(a), R * std::sin(a), 0);
      Vec3f n(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b));
      pts.push_back(makePoint(c + r * n, n, spacing, o));
    }
  addNoise(pts, o.noise * spacing, rng);
  return finish(std::move(pts));
}

TriangleMesh sphereMesh(float r, int subdivisions) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<Vec3f> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                            {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                            {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                            {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (Vec3f& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = uint32_t(v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> nf;
    for (auto& tri : f) {
      uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      nf.push_back({tri[0], a, c});
      nf.push_back({tri[1], b, a});
      nf.push_back({tri[2], c, b});
      nf.push_back({a, b, c});
    }
    f = std::move(nf);
  }
  TriangleMesh m;
  m.normals = v;
  for (Vec3f& p : v) p *= r;
  m.positions = std::move(v);
  m.faces = std::move(f);
  return m;
}

TriangleMesh gridMesh(int nx, int ny) {
  TriangleMesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      m.positions.emplace_back(float(i) / nx, float(j) / ny, 0.0f);
      m.normals.emplace_back(0, 0, 1);
    }
  auto id = [&](int i, int j) { return uint32_t(j * (nx + 1) + i); };
  auto uv = [&](int i, int j) { return Vec2f(float(i) / nx, float(j) / ny); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.cornerUVs.push_back({uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      m.cornerUVs.push_back({uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)});
    }
  return m;
}

HybridModel fold(double theta, double spacing, double noise, bool ridge, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::normal_distribution<double> g(0, 1);
  const double beta = (180 - theta) * std::numbers::pi / 180, W = 0.5;
  const Vec3d dirA(-1, 0, 0), dirB(std::cos(beta), 0, std::sin(beta));
  Vec3d nA(0, 0, 1), nB(-std::sin(beta), 0, std::cos(beta));
  if (ridge) nA = -nA, nB = -nB;
  HybridModel m;
  m.attributes.normals = true;
  const int nu = int(W / spacing), nv = int(1 / spacing);
  for (int sheet = 0; sheet < 2; ++sheet)
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const double u = (i + 0.5 + jitter(rng)) * spacing, v = -0.5 + (j + 0.5 + jitter(rng)) * spacing;
        const Vec3d& d = sheet ? dirB : dirA;
        const Vec3d& nrm = sheet ? nB : nA;
        const Vec3d p = u * d + Vec3d(0, v, 0) + noise * spacing * g(rng) * nrm;
        m.points.push_back({p.cast<float>(), nrm.cast<float>()});
      }
  return m;
}

}  // namespace linesurf::shapes
