// The certificate check of thesis §3.1.2.1 with the tolerances the extraction recorded.
#include "linesurf/pipeline/verify_job.h"

#include <cstdio>

#include "linesurf/core/options.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {

RecordedVerifyResult verifyAsRecorded(const HybridModel& input, const HybridModel& hybrid, const std::string& hybridName,
                                      const RecordedVerifyOptions& o) {
  if (o.epsilon) requireRange("epsilon", *o.epsilon, 0, 1e30);
  if (o.delta) requireRange("delta", *o.delta, 0, 2);
  if (o.k) requireRange("k", *o.k, 3, 256);
  if (o.surfaceError) validate(o.surface);
  RecordedVerifyResult r;
  double epsilon = -1, delta = -1;
  r.computedNormals = !input.attributes.normals;
  for (const std::string& c : hybrid.comments) {
    double e, d;
    int kk;
    if (std::sscanf(c.c_str(), "eps-delta: epsilon=%lf delta=%lf k=%d", &e, &d, &kk) == 3) {
      epsilon = e, delta = d;
      if (kk >= 3) r.k = kk;
    }
    if (c == "eps-delta: normals=computed") r.computedNormals = true;
  }
  if (o.epsilon) epsilon = *o.epsilon;
  if (o.delta) delta = *o.delta;
  if (o.k) r.k = *o.k;
  if (epsilon < 0 || delta < 0)
    throwBadOption("epsilon", hybridName + " records no tolerances (no 'eps-delta: epsilon=...' comment); "
                              "give epsilon and delta");
  r.epsilon = epsilon, r.delta = delta;
  GeometryOptions go;
  go.k = r.k;
  go.recomputeNormals = r.computedNormals;
  go.delaunayNeighbours = false;
  go.curvature = false;
  go.progress = o.progress;
  PointGeometry geo = computePointGeometry(input, go);
  r.report = verifyExtraction(input, &geo, hybrid, epsilon, delta);
  if (o.surfaceError) {
    // The input's surface with the normals the bound was checked against.
    HybridModel oriented = input;
    oriented.segments.clear();
    for (size_t i = 0; i < oriented.points.size(); ++i) oriented.points[i].normal = geo.normals[i];
    oriented.attributes.normals = true;
    if (o.progress) o.progress("surface error", 0.99);
    r.surface = SurfaceErrorReference(oriented, o.surface, geo.averageSpacing).measure(hybrid);
  }
  return r;
}

}  // namespace linesurf
