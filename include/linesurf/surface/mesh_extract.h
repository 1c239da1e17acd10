#pragma once
/// A triangle mesh of the surface a model implies (thesis §9.1, future work): the zero set of the
/// MLS function f of surface/mls.h over a sparse grid near the data, from a cloud, a hybrid or a
/// line model.
///
/// The grid is a cube lattice of edge `cellScale` x the model's median spacing, never stored
/// whole: cells are visited from the cells around the sources, across every cell face on which f
/// changes sign (surface following), and f is evaluated at their corners only. Each cube is cut
/// into the six tetrahedra of the Kuhn (Freudenthal) triangulation, which every neighbouring cube
/// cuts the same way, so marching tetrahedra has no ambiguous case and the mesh is a 2-manifold:
/// every edge is shared by two triangles, or by one on the mesh's boundary. A cell with a corner
/// out of every source's support (weight below `minWeight`) gives no triangles, so the mesh is open where the data
/// is open. Vertices lie on the tetrahedra's edges (linear interpolation of f), welded by edge, and
/// are then moved by one Newton step onto f = 0; triangles are wound so that their normal points
/// where f grows (the side the model's normals face). See docs/decisions.md "Meshes from the
/// implicit surface".
///
/// Deterministic: the same bytes for any thread count (corners are evaluated in parallel, each
/// into its own slot; cells, vertices and triangles are assembled in lattice order).
#include <cstddef>
#include <cstdint>

#include "linesurf/core/budget.h"
#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/surface/mls.h"

namespace linesurf {

struct MeshOptions {
  /// Cell edge, in the model's median spacings: [0.25, 4] and at most 0.4 x mls.supportScale
  /// (coarser cells reach out of the supports and open holes). 1 gives about two vertices per
  /// input point: finer adds triangles, not detail (the surface is smooth below its support
  /// radius, 3 spacings); coarser loses features below 2 cells.
  float cellScale = 1.0f;
  /// A corner whose sources' weights sum to less than this x the median spacing squared counts as
  /// out of reach: [0, 1]. A source's own weight is about its spacing squared, so 1e-3 leaves out
  /// the outer tenth of a lone source's support, where f rests on a sliver of one source (and a
  /// long segment's closed-form integral over the sliver has lost its digits).
  double minWeight = 1e-3;
  /// One Newton step from the interpolated vertex onto f = 0 (at most half a cell): the linear
  /// interpolation is off by O(cell^2 x curvature).
  bool project = true;
  /// The implicit surface (supportScale: its support radius h in spacings).
  MlsOptions mls;
  ProgressFn progress;  ///< called from the calling thread
};

/// Throws OptionError naming the field (cellScale, minWeight, or an MlsOptions field).
void validate(const MeshOptions& o);

struct MeshStats {
  double cellSize = 0;          ///< cell edge, object units
  double medianSpacing = 0;     ///< the model's, object units
  size_t sources = 0;           ///< points + segments
  size_t seedCells = 0;         ///< cells around the sources the search starts from
  size_t cells = 0;             ///< cells visited (corners evaluated)
  size_t surfaceCells = 0;      ///< cells with triangles
  size_t openCells = 0;         ///< cells f changes sign in but skipped: a corner out of every support
  size_t corners = 0;           ///< evaluations of f
  size_t vertices = 0, triangles = 0;
  size_t boundaryEdges = 0;     ///< edges of one triangle only (0: the mesh is closed)
  double estimatedBytes = 0;    ///< what the budget was asked for
  double surfaceSeconds = 0, gridSeconds = 0, meshSeconds = 0;
};

/// Working memory and output of meshing `model`, bytes, estimated before the work from the
/// sources alone (the surface a source stands for is about its spacing squared, so the cells the
/// surface crosses number about sources / cellScale^2): the MLS surface and its spacing, the
/// visited cells, corners and edges, and the mesh.
double meshBytesEstimate(const HybridModel& model, const MeshOptions& o = {});

/// The mesh of f = 0 (positions, unit vertex normals along grad f, faces). Throws Error:
/// BadParameter for bad options, for a model the MLS surface refuses (no points and no segments,
/// points without normals, a non-finite coordinate), for a grid finer than 2^20 cells along an
/// axis, and (naming budget.name()) when meshBytesEstimate exceeds `budget`; nothing has been
/// computed then. A model whose surface gives no triangle returns an empty mesh (stats say why).
TriangleMesh extractMesh(const HybridModel& model, const MeshOptions& o = {}, MeshStats* stats = nullptr,
                         const Budget& budget = Budget());

/// Edges of one triangle only, in a mesh whose faces index its positions.
size_t countBoundaryEdges(const TriangleMesh& mesh);

}  // namespace linesurf
