#pragma once
/// The surface error of an extraction (beyond the thesis: a §7 figure it could not compute, the
/// question of §9.1): how far the surface an extracted model implies lies from the surface of
/// what it was extracted from.
///
/// Both surfaces are MLS surfaces (surface/mls.h) under one rule: the reference's over the input
/// cloud's points as it has them (normals, and radii where it has them), the model's over its
/// points and segments as it has them; a kept point carries its input radius, so a model that
/// keeps every point reads 0. A
/// sample x is projected onto both; its error is the distance between the two projections.
/// Sampled both ways: the reference's points (a surface the model misses, a cap cut off, shows
/// here) and the model's primitives, its points and points along its segments every reference
/// spacing (a surface the model adds shows here). Each way takes at most `samples` samples by a
/// fixed stride over the list, so the figures are the same for any thread count.
///
/// A failed projection (surface/mls.h: a step left every support, no convergence) is counted,
/// never dropped: in its place the sample takes the source of the failed surface nearest to its
/// projection onto the other surface (the input point, or the model's sample), so a hole in the
/// model reads as the distance to the nearest primitive across it. A sample both projections
/// fail for takes the nearest source of each surface to itself, and is counted twice.
///
/// Against a mesh (contour models of §3.3) the reference surface is the triangle mesh itself:
/// projecting onto it is the closest point on its triangles, its samples are its vertices, and
/// its spacing is its mean edge length.
///
/// Figures are RMS, 99th percentile (nearest rank) and maximum, in object units; relative to
/// epsilonRef = 0.05 x the reference's average spacing (the thesis's epsilon, §7.2) and to the
/// model's bounding-box diagonal. See docs/decisions.md "The MLS surface".
#include <cstddef>
#include <cstdint>
#include <memory>

#include "linesurf/core/model.h"
#include "linesurf/surface/mls.h"

namespace linesurf {

/// epsilonRef as a fraction of the reference's average spacing (thesis §7.2's epsilon).
inline constexpr double kSurfaceErrorEpsilonRelative = 0.05;

struct SurfaceErrorOptions {
  /// Samples each way, at most, [100, 1e8]; more are thinned by a fixed stride. 20,000 puts the
  /// pooled 99th percentile on 400 samples: Igea's (eps, delta) hybrid reads RMS / 99% / max
  /// 0.518 / 1.48 / 4.15 eps_ref at 10,000 a way and 0.521 / 1.49 / 4.15 at 50,000, at about
  /// 45 us of CPU a sample (its two projections) on top of building the two surfaces.
  uint32_t samples = 20000;
  /// Both MLS surfaces (supportScale: the support radius h in spacings).
  MlsOptions mls;
};

/// Throws OptionError naming the field.
void validate(const SurfaceErrorOptions& o);

/// The figures of one set of samples (object units).
struct SurfaceErrorFigures {
  size_t samples = 0;
  size_t failedReference = 0;  ///< projections onto the reference surface that failed
  size_t failedModel = 0;      ///< projections onto the model's surface that failed
  double rms = 0, p99 = 0, max = 0, mean = 0;
};

struct SurfaceError {
  SurfaceErrorFigures fromReference;  ///< the reference's samples (input points, mesh vertices)
  SurfaceErrorFigures fromModel;      ///< the model's samples (points, points along segments)
  SurfaceErrorFigures both;           ///< the two pooled: the figure to quote
  double referenceSpacing = 0;        ///< average spacing (cloud) or mean edge length (mesh)
  double epsilonRef = 0;              ///< kSurfaceErrorEpsilonRelative x referenceSpacing
  double diagonal = 0;                ///< the model's bounding-box diagonal
  bool meshReference = false;
  size_t failures() const { return both.failedReference + both.failedModel; }
};

/// A reference surface, built once and measured against any number of models.
class SurfaceErrorReference {
 public:
  /// The MLS surface of `cloud`'s points (segments ignored), which need unit normals.
  /// `averageSpacing`: the cloud's §6.1 average spacing when the caller has it (0: computed).
  /// Throws Error (BadParameter "cloud") for an empty cloud, one without normals, a non-finite
  /// coordinate or a normal that is not unit; OptionError for bad options.
  explicit SurfaceErrorReference(const HybridModel& cloud, const SurfaceErrorOptions& o = {}, double averageSpacing = 0);
  /// The mesh itself. Throws Error (BadParameter "mesh") for a mesh without faces, a face index
  /// out of range or a non-finite vertex.
  explicit SurfaceErrorReference(const TriangleMesh& mesh, const SurfaceErrorOptions& o = {});
  ~SurfaceErrorReference();
  SurfaceErrorReference(SurfaceErrorReference&&) noexcept;
  SurfaceErrorReference& operator=(SurfaceErrorReference&&) noexcept;

  /// Throws Error (BadParameter "model") for a model the MLS surface refuses (no points and no
  /// segments, points without normals, a non-finite coordinate). Deterministic for any thread
  /// count; parallel.
  SurfaceError measure(const HybridModel& model) const;
  double spacing() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One model against one cloud / mesh (SurfaceErrorReference(...).measure(model)).
SurfaceError surfaceError(const HybridModel& cloud, const HybridModel& model, const SurfaceErrorOptions& o = {});
SurfaceError surfaceError(const TriangleMesh& mesh, const HybridModel& model, const SurfaceErrorOptions& o = {});

}  // namespace linesurf
