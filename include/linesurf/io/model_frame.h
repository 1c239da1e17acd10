#pragma once
/// Scale-free processing: results must not depend on the model's units. Float arithmetic does
/// (squared distances of a model 1e-12 across underflow, of one 1e12 across overflow), so the
/// CLI moves a model whose size is far from 1 into a normalised frame before the geometry and
/// rendering stages, and maps what it reports back. Normalising scales by a power of two (exact
/// in floating point) and translates by the bounds' centre; a model whose bounding radius lies
/// within [2^-10, 2^20] and whose centre is near it is left untouched (identity frame), so
/// ordinary models give bit-identical results.
#include "linesurf/core/model.h"

namespace linesurf {

struct ModelFrame {
  Vec3d centre = Vec3d::Zero();  ///< object-space point mapped to the origin
  double scale = 1;              ///< object units per normalised unit (a power of two)
  bool identity() const { return scale == 1 && centre.isZero(); }
  Vec3f toNormalized(const Vec3f& p) const { return ((p.cast<double>() - centre) / scale).cast<float>(); }
  Vec3f toObject(const Vec3f& p) const { return (p.cast<double>() * scale + centre).cast<float>(); }
};

/// The frame that normalises bounds `b` (identity when normalising is not needed).
ModelFrame normalizingFrame(const Bounds3f& b);

/// Moves positions and radii (points, segment ends, mesh vertices) into `frame`.
void toFrame(HybridModel& model, const ModelFrame& frame);
void toFrame(TriangleMesh& mesh, const ModelFrame& frame);

}  // namespace linesurf
