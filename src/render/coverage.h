#pragma once
/// Coverage alpha (RenderOptions::coverageGain; beyond the thesis, see docs/decisions.md, "Coverage alpha
/// (opt-in)"): the area each
/// primitive stands for. Internal to the pipeline (renderer.cpp).
///
/// The renderer's fragments carry resampling weights w_k(x) (normalised Gaussians in object space,
/// times 2 pi; a segment's integrated along it, so that it weighs as length / radius points). The
/// sum of the weights over a surface is its kernel density, which varies with the sampling; a pixel's
/// coverage is that sum divided by the density itself: sum_k c_k w_k(x) with c_k = 1 / min sum_j
/// w_j(x), the inverse of the model's least kernel density around the primitive (x: its centre and
/// a ring at 0.6 r in its plane; a Shepard normalisation that also lifts the troughs between
/// samples; a point's weights are scaled by its mass, pointMasses). Inside a surface it is >= ~1
/// whatever the sampling; past a silhouette it falls off with the kernels' tails, as a box-filtered
/// mesh's coverage does. The density counts the primitives of the
/// same sheet only (normals within 90 degrees, centre within the kernel's cut-off of the plane), so
/// that the two sides of a thin part do not halve each other's coverage.
#include <cstdint>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/model.h"

namespace linesurf::detail {

/// c_k for the points, then the segments, of `model` (0 for a primitive without a positive finite
/// radius), with the reconstruction kernels sigma = reconstructionScale * radius cut off at `cutoff`
/// standard deviations, without the screen prefilter (it keeps a kernel's mass). Deterministic for
/// any thread count. The density around k is sampled at its centre and on a ring at 0.6 r in its
/// plane; `least`: c_k inverts the least of them (coverage everywhere, RenderOptions::coverageReach
/// 0: the troughs between samples reach 1 and the interior stays opaque), otherwise their mean
/// (coverage at silhouettes only, where the interior is opaque anyway: the edge of a sampling then
/// ends within half a cell of its samples' cells, as a box-filtered surface's does; the least
/// density moved a grid of points' edge out by 1.8 half cells; docs/decisions.md, "Coverage alpha
/// (opt-in)"). stride > 1: only every stride-th primitive's constant is computed (the others are 0;
/// RenderOptions::tailCoverage takes the median of a sample).
std::vector<float> coverageConstants(const HybridModel& model, float reconstructionScale, float cutoff, bool least = true,
                                     size_t stride = 1);

/// The median of coverageConstants(model, reconstructionScale, cutoff, false) over a sample of at
/// most ~4096 primitives, evenly strided (RenderOptions::tailCoverage); 0 for a model without a
/// usable primitive.
float medianCoverageConstant(const HybridModel& model, float reconstructionScale, float cutoff);

}  // namespace linesurf::detail
