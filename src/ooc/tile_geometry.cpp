// The per-tile geometry stage of the out-of-core pipeline (see tile_geometry.h): each tile with
// its halo through the in-memory §6.1 code, its results (and, for an extraction, its own points'
// geometry) written to files of its own.
#include "ooc/tile_geometry.h"

#include <algorithm>
#include <numeric>

#include "geometry/detail/point_geometry_tile.h"

namespace linesurf::ooc::detail {
namespace {

/// One tile with its halo through computePointGeometryTile: the halo is widened until every
/// interior point's queries stay inside it (or it is one tile wide).
struct TileGeometry {
  Points all;                   ///< interior + halo, in input order
  std::vector<uint32_t> owner;  ///< tile of each point of `all`
  std::vector<uint8_t> exact;   ///< per point of `all`: its queries stayed inside the halo
  HybridModel model;
  std::vector<float> ownAttrs;  ///< the tile's own points' attributes, in input order
  PointGeometry geo;
  linesurf::detail::TileGeometryExtras extras;
  uint64_t inexact = 0;
  uint32_t widenings = 0;
};

TileGeometry tileGeometry(const Run& r, uint32_t tile, bool delaunay) {
  const size_t rs = r.recordBytes();
  Points interior;
  r.decode(readRange(r.cellPath(tile), 0, r.tileCounts[r.denseOf.at(tile)] * rs), interior);
  Vec3d bmin, bmax;
  r.tileBox(tile, bmin, bmax);
  const double width = r.tileWidth(tile);
  // Neighbour tiles that hold points within one tile width of the box (the widest halo), and
  // whether a face of the box has no point beyond it.
  std::vector<uint32_t> neighbours;
  bool openLow[3], openHigh[3];
  const bool onGrid = tile < r.gridTiles();
  if (onGrid) {
    // A tile of the grid: the tiles of its 26-ring (or their refinements' tiles); a face on the
    // grid's border has none beyond it.
    const Grid& g = r.grid;
    const auto c = g.coords(tile);
    for (uint32_t u : r.tileIds) {
      if (u == tile) continue;
      const auto cu = g.coords(r.gridAncestor(u));
      bool ring = true;
      for (int a = 0; a < 3; ++a) ring = ring && std::abs(cu[size_t(a)] - c[size_t(a)]) <= 1;
      if (ring) neighbours.push_back(u);
    }
    for (int a = 0; a < 3; ++a) openLow[a] = c[size_t(a)] == 0, openHigh[a] = c[size_t(a)] == g.tiles[size_t(a)] - 1;
  } else {
    // A tile of a refinement: every tile whose points' box reaches the widest halo.
    for (size_t d = 0; d < r.tileIds.size(); ++d) {
      const Bounds3f& b = r.tileBounds[d];
      if (r.tileIds[d] == tile) continue;
      bool near = true;
      for (int a = 0; a < 3; ++a) near = near && double(b.max[a]) >= bmin[a] - width && double(b.min[a]) <= bmax[a] + width;
      if (near) neighbours.push_back(r.tileIds[d]);
    }
  }
  // Beyond the halo of width h: a face of a refinement's tile is open when no point of the cloud
  // lies past it.
  auto setOpen = [&](double h) {
    if (onGrid) return;
    for (int a = 0; a < 3; ++a)
      openLow[a] = double(r.bounds.min[a]) >= bmin[a] - h, openHigh[a] = double(r.bounds.max[a]) <= bmax[a] + h;
  };

  GeometryOptions go = r.o.geometry;
  go.curvature = r.tileCurvature();
  go.delaunayNeighbours = delaunay || go.curvature;
  // The cover radius is the radius `normals` writes; the extractions do not use it.
  go.coverRadius = !r.extracting();
  go.progress = {};
  double h = width * kHaloStart;
  TileGeometry tg;
  // The attributes go to the extraction only (own points, in the cell's order, which is the
  // input's); the geometry does not use them.
  tg.ownAttrs = std::move(interior.att);
  interior.att.clear();
  for (;;) {
    setOpen(h);
    // Halo: the neighbours' points inside the box widened by h.
    Points all = interior;
    std::vector<uint32_t> owner(interior.size(), tile);
    for (uint32_t u : neighbours) {
      Points p;
      r.decode(readRange(r.cellPath(u), 0, r.tileCounts[r.denseOf.at(u)] * rs), p, false);
      for (size_t i = 0; i < p.size(); ++i) {
        const Vec3d q = p.pos[i].cast<double>();
        if ((q.array() >= bmin.array() - h).all() && (q.array() <= bmax.array() + h).all()) {
          all.idx.push_back(p.idx[i]);
          all.pos.push_back(p.pos[i]);
          if (r.normalsIn) all.nrm.push_back(p.nrm[i]);
          if (r.radiusIn) all.rad.push_back(p.rad[i]);
          owner.push_back(u);
        }
      }
    }
    // In the input's order, so that ties between equal distances break as in memory.
    const size_t n = all.size();
    std::vector<uint32_t> perm(n);
    std::iota(perm.begin(), perm.end(), 0u);
    std::sort(perm.begin(), perm.end(), [&](uint32_t a, uint32_t b) { return all.idx[a] < all.idx[b]; });
    tg.all = Points();
    tg.owner.resize(n);
    tg.model = HybridModel();
    tg.model.points.resize(n);
    for (size_t i = 0; i < n; ++i) {
      tg.all.idx.push_back(all.idx[perm[i]]);
      tg.all.pos.push_back(all.pos[perm[i]]);
      tg.owner[i] = owner[perm[i]];
      tg.model.points[i].position = all.pos[perm[i]];
      if (r.normalsIn) tg.model.points[i].normal = all.nrm[perm[i]];
      if (r.radiusIn) tg.model.points[i].radius = all.rad[perm[i]];
    }
    tg.model.attributes.normals = r.normalsIn;
    tg.model.attributes.radii = r.radiusIn;
    tg.geo = linesurf::detail::computePointGeometryTile(tg.model, go, r.dupTol, &tg.extras);
    // Distance from a point to the halo's outer boundary (faces on the grid's border: none).
    auto room = [&](const Vec3f& pf) {
      const Vec3d p = pf.cast<double>();
      double d = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (!openLow[a]) d = std::min(d, p[a] - (bmin[a] - h));
        if (!openHigh[a]) d = std::min(d, (bmax[a] + h) - p[a]);
      }
      return d;
    };
    tg.exact.assign(n, 0);
    tg.inexact = 0;
    // A point with fewer than k neighbours here has more elsewhere unless the whole cloud is here
    // (a far outlier alone in its tile: its queries found nothing, they did not stay inside).
    const size_t k = size_t(tg.geo.k);
    const bool whole = n == r.info.count;
    for (size_t i = 0; i < n; ++i) {
      const bool full = whole || k == 0 || tg.geo.neighbours[i * k + k - 1] != PointGeometry::kNoNeighbour;
      tg.exact[i] = full && double(tg.extras.reach[i]) < room(tg.all.pos[i]);
      if (tg.owner[i] == tile && !tg.exact[i]) ++tg.inexact;
    }
    if (tg.inexact > 0 && h < width) {
      h = std::min(2 * h, width);
      ++tg.widenings;
      continue;
    }
    return tg;
  }
}

OwnGeometry ownGeometry(const TileGeometry& tg, uint32_t tile, bool curvature) {
  const PointGeometry& g = tg.geo;
  const size_t n = tg.all.size();
  OwnGeometry og;
  std::vector<uint32_t> local(n, PointGeometry::kNoNeighbour);
  for (size_t i = 0; i < n; ++i)
    if (tg.owner[i] == tile) local[i] = uint32_t(og.idx.size()), og.idx.push_back(tg.all.idx[i]);
  og.attrs = tg.ownAttrs;  // own points in input order, as og.idx
  og.starOffsets.push_back(0);
  for (size_t i = 0; i < n; ++i) {
    if (local[i] == PointGeometry::kNoNeighbour) continue;
    og.pos.push_back(tg.all.pos[i]);
    og.normal.push_back(g.normals[i]);
    og.radius.push_back(tg.model.points[i].radius);  // the input's, as the extractions keep it in memory
    og.spacing.push_back(g.spacing[i]);
    og.variation.push_back(g.surfaceVariation[i]);
    og.component.push_back(tg.extras.component.empty() ? 0 : tg.extras.component[i]);
    og.flags.push_back(g.flags[i]);
    if (curvature) og.minDir.push_back(g.minCurvatureDir[i]), og.maxDir.push_back(g.maxCurvatureDir[i]);
    for (uint32_t q : g.delaunayOf(i))
      if (local[q] != PointGeometry::kNoNeighbour) og.star.push_back(local[q]);
    og.starOffsets.push_back(uint32_t(og.star.size()));
  }
  return og;
}

}  // namespace

/// Processes one tile for the normals: writes its result file.
void processTile(const Run& r, uint32_t tile) {
  TileGeometry tg = tileGeometry(r, tile, r.extracting());
  const PointGeometry& geo = tg.geo;
  const linesurf::detail::TileGeometryExtras& extras = tg.extras;
  const size_t n = tg.all.size();
  TileSummary sum;
  sum.tile = tile;
  sum.widenings = tg.widenings;
  const uint64_t inexact = tg.inexact;
  {
    // Results of the interior points (in index order = the cell file's order).
    const bool oriented = !extras.component.empty();
    uint32_t comps = 0;
    for (uint32_t cpt : extras.component) comps = std::max(comps, cpt + 1);
    if (!oriented) comps = 1;
    std::vector<InteriorResult> res;
    res.reserve(n);
    std::map<uint32_t, std::vector<SharedPoint>> shared;
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> votesOf;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t comp = oriented ? extras.component[i] : 0;
      const uint64_t gi = tg.all.idx[i];
      if (tg.owner[i] != tile) {
        // A shared point: its normal here votes on the orientation of the two tiles when its
        // queries stayed inside this halo (then it is the owner's normal up to sign).
        // At most kVotesPerPair per (owner, component): exact shared normals vote unanimously, and
        // the cap bounds what the join holds in memory (20% of the points would be shared).
        if (tg.exact[i] && ++votesOf[{tg.owner[i], comp}] <= kVotesPerPair) shared[tg.owner[i]].push_back({gi, comp, geo.normals[i]});
        continue;
      }
      InteriorResult x;
      x.normal = geo.normals[i];
      x.cover = geo.coverRadius.empty() ? 0.0f : geo.coverRadius[i];  // none in the extraction's first pass
      x.spacing = geo.spacing[i];
      x.component = comp;
      x.flags = geo.flags[i];
      res.push_back(x);
      if (geo.neighbours[i * size_t(geo.k)] != PointGeometry::kNoNeighbour) sum.spacingSum += geo.spacing[i], ++sum.spacingCount;
      if (x.flags & kPointDuplicate) ++sum.flagCounts[0];
      if (x.flags & kPointFewNeighbours) ++sum.flagCounts[1];
      if (x.flags & kPointFlatNeighbourhood) ++sum.flagCounts[2];
      if (x.flags & kPointIsolated) ++sum.flagCounts[3];
    }
    // What the tile's own points say about each component's side: the join adds the pieces up.
    std::vector<SideSummary> sides(comps);
    if (oriented) {
      std::vector<uint8_t> own(n);
      for (size_t i = 0; i < n; ++i) own[i] = tg.owner[i] == tile;
      sides = linesurf::detail::sideSummaries(r.o.geometry.orient, r.o.geometry.viewpoint, linesurf::detail::SideGrid(r.bounds),
                                              tg.all.pos, geo.normals, extras.component, comps, tg.all.idx, own);
    }
    sum.interior = uint32_t(res.size());
    sum.components = comps;
    sum.inexact = inexact;
    sum.withHalo = uint32_t(n);
    if (r.curvatureOut()) {  // before the result file, whose presence marks the tile done
      std::string c;
      c.reserve(res.size() * kCurvatureRecord);
      for (size_t i = 0; i < n; ++i)
        if (tg.owner[i] == tile)
          putRaw(c, geo.kMin[i]), putRaw(c, geo.kMax[i]), putRaw(c, geo.minCurvatureDir[i]), putRaw(c, geo.maxCurvatureDir[i]);
      writeWhole(r.curvaturePath(tile), sealed(r, Stage::Curvature, tile, std::move(c)));
    }
    if (r.extracting()) writeWhole(r.ownGeometryPath(tile), sealed(r, Stage::Geometry, tile, encodeOwnGeometry(ownGeometry(tg, tile, r.tileCurvature()))));
    writeWhole(r.resultPath(tile), sealed(r, Stage::Result, tile, encodeResult(sum, res, sides, shared)));
  }
}

}  // namespace linesurf::ooc::detail
