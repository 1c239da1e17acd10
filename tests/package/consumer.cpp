// Uses the installed package: §6.1 normals of a sampled sphere, then a render of it.
#include <cmath>
#include <cstdio>

#include <linesurf/geometry/point_geometry.h>
#include <linesurf/pipeline/render_job.h>
#include <linesurf/render/renderer.h>

int main() {
  using namespace linesurf;
  HybridModel cloud;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {  // Fibonacci sphere of radius 1
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z), a = i * 2.399963229728653;
    cloud.points.push_back(Point{.position = Vec3f(float(r * std::cos(a)), float(r * std::sin(a)), float(z))});
  }
  PointGeometry geo = computePointGeometry(cloud, {.k = 12, .curvature = false});
  int outward = 0;
  for (int i = 0; i < n; ++i) outward += geo.normals[i].dot(cloud.points[i].position) > 0.99f;
  applyGeometry(cloud, geo);
  Renderer renderer(cloud);
  RenderResult r = renderer.render(viewCameras(renderer.sphere(), {.width = 64, .height = 64})[0]);
  int covered = 0;
  for (const Color& c : r.color.pixels) covered += c.x() < 0.99f;
  std::printf("consumer: %d points, %d normals outward, %dx%d image, %d pixels covered\n", n, outward, r.color.width,
              r.color.height, covered);
  return outward == n && covered > 1000 ? 0 : 1;
}
