// A point cloud -> (epsilon, delta) hybrid model (thesis §3.1) -> renders of both from one camera
// -> image metrics (§7), with the installed linesurf package. Usage: hybrid_example CLOUD OUTDIR
#include <cstdio>
#include <exception>
#include <filesystem>

#include <linesurf/eval/image_metrics.h>
#include <linesurf/extract/eps_delta.h>
#include <linesurf/geometry/point_geometry.h>
#include <linesurf/io/image_io.h>
#include <linesurf/io/model_io.h>
#include <linesurf/pipeline/render_job.h>
#include <linesurf/render/renderer.h>

int main(int argc, char** argv) try {
  using namespace linesurf;
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s CLOUD.ply OUTDIR\n", argv[0]);
    return 1;
  }
  const std::filesystem::path out = argv[2];
  std::filesystem::create_directories(out);

  HybridModel cloud = readModel(argv[1]);
  PointGeometry geo = computePointGeometry(cloud, {.k = 12, .curvature = false});  // §6.1
  applyGeometry(cloud, geo);  // normals + radii: the cloud renders, and the kept points keep its radii
  EpsDeltaStats stats;
  HybridModel hybrid = extractEpsDelta(cloud, geo, {.epsilonRelative = 0.05, .delta = 0.004}, &stats);
  std::printf("%zu points -> %zu points + %zu segments (%.1f%% data reduction)\n", cloud.points.size(),
              stats.keptPoints, stats.segments, 100 * stats.dataReduction());

  // The default view; the hybrid's own default camera would be the same (it spans the cloud's extent).
  const Camera camera = viewCameras(boundingSphere(cloud), {.width = 512, .height = 512})[0];
  const Image points = renderImage(cloud, camera).color, lines = renderImage(hybrid, camera).color;
  writePng(out / "points.png", points, false);
  writePng(out / "hybrid.png", lines, false);
  const ImageMetrics m = compareImages(points, lines);
  std::printf("hybrid vs points: mse %.6f, psnr %.2f dB, ssim %.4f -> %s\n", m.mse, m.psnr, m.ssim, out.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "%s\n", e.what());
  return 1;
}
