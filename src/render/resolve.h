#pragma once
/// The resolve of a Z^3 tile (thesis §6.2.3, step 2) for its pixels with one layer, in SIMD rows
/// (resolve.cpp): the renderer's stage 4 for nearly every pixel; Z3Tile::resolve does the rest.
#include <vector>

#include "z3_buffer.h"

namespace linesurf::detail {

struct SilhouettePixel;  // coverage.h

/// The resolve of one row of a Z^3 tile without deferred shading (renderer stage 3), in SIMD:
/// of the pixels x0 .. x0 + n - 1 of row y, the first `returned` ones (whole vectors) that hold
/// exactly one layer get Z3Tile::resolve's colour composited over the background bg (r, g, b, a)
/// the way the renderer does, written to out (straight RGBA, 4 floats per pixel from x0); the
/// other pixels before `returned` (empty, or several layers) get bg itself, the pixels from
/// `returned` on are left to the caller. out is only written (it may be uninitialised). `others`:
/// whether any of the pixels before `returned` holds several layers. frontZ (coverage at
/// silhouettes only, src/render/coverage.h): the front depths of the pixels before `returned`
/// (+inf where empty) go to frontZ[0 ..], the one-layer pixels are written with an opaque front
/// layer, and those partly covered are appended to cands with their coverage result.
int resolveSingleLayerRow(Z3Tile& tile, int y, int x0, int n, const float* bg, float* out, bool& others,
                          float* frontZ = nullptr, std::vector<SilhouettePixel>* cands = nullptr);

}  // namespace linesurf::detail
