// Feature lines side by side: linesurf's `extract features` (extract/feature_lines.h) against
// CGAL's Voronoi covariance measure (Mérigot, Ovsjanikov & Guibas 2011; compute_vcm +
// vcm_is_on_feature_edge) on folds with a known crease (tests/shapes.h), dihedral angles 30-150
// degrees, noise 0.1 spacing. Precision and recall by length within 2 spacings of the crease:
// for linesurf along its segments, for VCM over its flagged points (precision: the share of
// them within 2 spacings; recall: the share of the crease within 2 spacings of one). Times on
// the same machine, one run each.
// Usage: feature_peers [--spacing S] [--noise N] [--vcm-offset R] [--vcm-convolution r] [--vcm-threshold T]
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/vcm_estimate_edges.h>
#include <CGAL/vcm_estimate_normals.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include "linesurf/extract/feature_lines.h"
#include "shapes.h"

using linesurf::Vec3d;

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double toCrease(const Vec3d& x) {  // the crease: x = z = 0, |y| <= 0.5
  const double y = std::clamp(x.y(), -0.5, 0.5);
  return (x - Vec3d(0, y, 0)).norm();
}

struct Score {
  double precision = 0, recall = 0;
  double f1() const { return precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0; }
};

/// Precision over `samples` (points along the detected features), recall over the crease. With
/// `border` > 0, samples within that distance of a sheet's free border (|y| = 0.5, or 0.5 from
/// the crease) are left out: VCM marks borders as it marks creases.
Score score(std::vector<Vec3d> samples, double tol, double border = 0) {
  Score s;
  if (border > 0)
    std::erase_if(samples, [&](const Vec3d& x) { return std::abs(x.y()) > 0.5 - border || toCrease(x) > 0.5 - border; });
  if (samples.empty()) return s;
  size_t on = 0;
  for (const Vec3d& x : samples) on += toCrease(x) <= tol;
  s.precision = double(on) / double(samples.size());
  const int steps = 400;
  int covered = 0;
  for (int k = 0; k < steps; ++k) {
    const Vec3d c(0, -0.5 + (k + 0.5) / steps, 0);
    for (const Vec3d& x : samples)
      if ((x - c).norm() <= tol) {
        ++covered;
        break;
      }
  }
  s.recall = double(covered) / steps;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  // VCM's radii in spacings: offset R (the Voronoi cells' reach), convolution r; threshold on
  // the second eigenvalue's share (CGAL's example: 0.16).
  double spacing = 1.0 / 60, noise = 0.1, offset = 5, convolution = 2, threshold = 0.16;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--spacing")) spacing = std::stod(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--noise")) noise = std::stod(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--vcm-offset")) offset = std::stod(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--vcm-convolution")) convolution = std::stod(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--vcm-threshold")) threshold = std::stod(argv[i + 1]);
  }
  const double R = offset * spacing, r = convolution * spacing, tol = 2 * spacing;
  fmt::print("folds: spacing {:.4g}, noise {} x spacing; within {} spacings of the crease; VCM R = {}, r = {} spacings, "
             "threshold {}\n", spacing, noise, tol / spacing, offset, convolution, threshold);
  fmt::print("| dihedral | points | linesurf P / R / F1 | time | CGAL VCM P / R / F1 | away from the borders | time |\n"
             "|---|---:|---|---:|---|---|---:|\n");
  for (double theta : {30.0, 60.0, 90.0, 120.0, 150.0})
    for (bool ridge : {true, false}) {
      const linesurf::HybridModel m = linesurf::shapes::fold(theta, spacing, noise, ridge, uint64_t(theta) + ridge);
      auto t0 = std::chrono::steady_clock::now();
      const linesurf::HybridModel lines = linesurf::extractFeatureLines(m);
      const double tl = seconds(t0);
      std::vector<Vec3d> along;
      for (const linesurf::Segment& s : lines.segments) {
        const int steps = std::max(1, int(s.length() / (0.2 * spacing)));
        for (int k = 0; k < steps; ++k) along.push_back((s.p0 + (s.p1 - s.p0) * ((k + 0.5f) / float(steps))).cast<double>());
      }
      const Score sl = score(along, tol);
      std::vector<Kernel::Point_3> pts;
      for (const linesurf::Point& p : m.points) pts.emplace_back(p.position.x(), p.position.y(), p.position.z());
      t0 = std::chrono::steady_clock::now();
      std::vector<std::array<double, 6>> cov;
      CGAL::compute_vcm(pts, cov, R, r, CGAL::parameters::geom_traits(Kernel()));
      std::vector<Vec3d> flagged;
      for (size_t i = 0; i < pts.size(); ++i)
        if (CGAL::vcm_is_on_feature_edge(cov[i], threshold)) flagged.emplace_back(pts[i].x(), pts[i].y(), pts[i].z());
      const double tv = seconds(t0);
      const Score sv = score(flagged, tol), sb = score(flagged, tol, 3 * spacing);
      fmt::print("| {:.0f}° {} | {} | {:.3f} / {:.3f} / {:.3f} | {:.2f} s | {:.3f} / {:.3f} / {:.3f} | {:.3f} / {:.3f} / {:.3f} | "
                 "{:.2f} s |\n", theta, ridge ? "ridge" : "valley", m.points.size(), sl.precision, sl.recall, sl.f1(), tl,
                 sv.precision, sv.recall, sv.f1(), sb.precision, sb.recall, sb.f1(), tv);
    }
  return 0;
}
