#pragma once
/// The surface a point model implies (thesis §9.1, future work): an implicit moving-least-squares
/// surface over the model's oriented points, Kolluri's IMLS (2005) with a compactly supported
/// kernel, each point a source weighted by the area it stands for:
///
///   f(x) = sum_i a_i phi_i(x) n_i . (x - p_i) / sum_i a_i phi_i(x),
///   phi_i(x) = (1 - |x - p_i|^2 / h_i^2)^4 inside the support |x - p_i| < h_i, else 0,
///
/// with a_i = r_i^2 (the splat's radius, else the point's spacing), h_i = supportScale x the
/// point's spacing; a segment adds the same terms integrated along its length. f is a signed distance near the surface, positive on the side the normals
/// face; the surface is f = 0. Its gradient and Hessian are exact (closed form), so are the
/// principal curvatures and directions of its level sets, and projection is Newton's step along
/// the gradient. The kernel is a polynomial in the squared distance so that line-segment sources
/// can be integrated along their length in closed form. See docs/decisions.md "The MLS surface".
#include <cstdint>
#include <memory>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/model.h"

namespace linesurf {

struct MlsOptions {
  /// h_i = supportScale x spacing_i: [1.5, 10]; 3 keeps about 28 sources in reach on an even
  /// sampling (the fit needs more than a point's 12 neighbours to be smooth across them).
  float supportScale = 3.0f;
  /// Projection: at most this many Newton steps, [1, 1000].
  int maxIterations = 20;
  /// Projection has converged when |f| and the last step are below tolerance x the local
  /// support radius, (0, 0.1].
  float tolerance = 1e-5f;
  /// Beyond IMLS: RIMLS (Öztireli, Guennebaud & Gross 2009), which keeps creases. f is refitted
  /// `robustIterations` times with each source's weight multiplied by
  /// exp(-((d_i - f) / (sigmaResidual h_i))^2) exp(-|n_i - grad f / |grad f||^2 / sigmaNormal^2)
  /// from the previous fit, so that sources across a crease (whose normals disagree with the
  /// fit's) stop pulling the surface round. The gradient is the paper's (the refit weights held
  /// constant), the Hessian and the normal field's Jacobian those of the last fit's sum.
  bool robust = false;
  /// Refits, [1, 10].
  int robustIterations = 3;
  /// Normal term's scale on |n_i - n|, (0, 4]: 0.75 lets sources within about 40 degrees of the
  /// fit's normal keep most of their weight.
  float sigmaNormal = 0.75f;
  /// Residual term's scale, x h_i, (0, 10].
  float sigmaResidual = 0.5f;
};

/// Throws Error(BadParameter) naming the field.
void validate(const MlsOptions& o);

/// f and its derivatives at a point of space.
struct MlsSample {
  double value = 0;                ///< f(x): signed distance, positive where the normals face
  Vec3d gradient = Vec3d::Zero();  ///< exact
  Mat3d hessian = Mat3d::Zero();   ///< exact
  /// The sources' normals averaged by their weights (unnormalised), and its Jacobian (exact).
  Vec3d normalField = Vec3d::Zero();
  Mat3d normalJacobian = Mat3d::Zero();
  double weight = 0;               ///< sum of the sources' weights: 0 outside every support
  uint32_t sources = 0;            ///< sources in reach
  bool valid() const { return weight > 0; }
};

/// The principal curvatures at x: the eigen-decomposition, in the tangent plane, of the shape
/// operator of the MLS normal field n = m / |m|, m = the sources' normals averaged by their
/// weights (exact derivatives). Positive where the surface bends away from its normal (a sphere
/// with outward normals: +1/r), as the §6.1.2 curvature of point_geometry.h.
struct MlsCurvature {
  double kMin = 0, kMax = 0;
  Vec3d dirMin = Vec3d::Zero(), dirMax = Vec3d::Zero();  ///< unit, tangent, dirMin x dirMax = n
  Vec3d normal = Vec3d::Zero();
  bool valid = false;  ///< false where no source reaches or the gradient vanishes
};

struct MlsProjection {
  Vec3d point = Vec3d::Zero();
  Vec3d normal = Vec3d::Zero();
  int iterations = 0;
  /// False when a step left every support, the gradient vanished, or maxIterations passed
  /// without reaching the tolerance: the point is then the last iterate.
  bool converged = false;
};

class MlsSurface {
 public:
  /// The model's points and segments are the sources. Points need normals (attributes.normals;
  /// unit, oriented); their radii (else their spacing) give the areas. A segment is its strip:
  /// weight 2 x radius per unit length, support supportScale x radius, its normal interpolated
  /// linearly between its endpoint normals where the model has them; its terms are integrated
  /// along it in closed form.
  explicit MlsSurface(const HybridModel& model, const MlsOptions& options = {});
  ~MlsSurface();
  MlsSurface(MlsSurface&&) noexcept;
  MlsSurface& operator=(MlsSurface&&) noexcept;

  /// f and its derivatives at x; without `secondDerivatives` the Hessian and the normal
  /// field's Jacobian are left zero (a third of the work, what projection needs).
  MlsSample evaluate(const Vec3d& x, bool secondDerivatives = true) const;
  MlsCurvature curvature(const Vec3d& x) const;
  MlsProjection project(const Vec3d& x) const;
  /// The support radius of the nearest source to x (the length tolerances are relative to).
  double localSupport(const Vec3d& x) const;
  size_t sources() const;
  /// The median spacing of the points (of the strips' half-widths for a model of segments alone):
  /// the unit of the supports, and of a mesh's cells (surface/mesh_extract.h).
  double medianSpacing() const;

 private:
  struct Impl;
  /// One fit's sums at x; with `fit` (the previous fit's f and unit normal) the robust weights.
  MlsSample accumulate(const Vec3d& x, bool second, const MlsSample* fit) const;
  std::unique_ptr<Impl> impl_;
};

}  // namespace linesurf
