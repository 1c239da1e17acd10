// Choosing a level-of-detail hierarchy's nodes for a view, assembling them and rendering them
// with a splat budget (include/linesurf/lod/lod.h; the §6.2 pipeline through the public
// Renderer). The file itself is read and validated in lod_file.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <queue>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/lod/lod.h"
#include "lod_format.h"

namespace linesurf::lod {
Selection selectNodes(const LodFile& file, const Camera& camera, uint64_t budget) {
  const auto& nodes = file.nodes();
  const LodHeader& h = file.header();
  Selection sel;
  if (budget >= h.points + h.segments) {  // everything: the full model's picture
    for (uint32_t i = 0; i < nodes.size(); ++i)
      if (nodes[i].leaf) sel.nodes.push_back(i), sel.primitives += nodes[i].count();
    return sel;
  }
  const auto planes = camera.frustumPlanes();
  std::vector<char> inCut(nodes.size(), 0);
  auto visible = [&](uint32_t i) {
    const NodeInfo& n = nodes[i];
    const Vec3f c = camera.toCamera(n.boundsMin * 0.5f + n.boundsMax * 0.5f);
    const float r = 0.5f * (n.boundsMax - n.boundsMin).norm();
    for (const Vec4f& pl : planes) {
      const float len = pl.head<3>().norm();
      if (len > 0 && (pl.head<3>().dot(c) + pl.w()) / len < -r) return false;
    }
    return true;
  };
  auto priority = [&](uint32_t i) {
    const NodeInfo& n = nodes[i];
    const Vec3f c = 0.5f * (n.boundsMin + n.boundsMax);
    const float r = 0.5f * (n.boundsMax - n.boundsMin).norm();
    const float d = (c - camera.eye()).norm() - r;
    return r / std::max(d, 1e-6f * std::max(r, 1e-30f));  // projected size, up to the focal length
  };
  using Item = std::pair<float, uint32_t>;
  auto cmp = [](const Item& a, const Item& b) { return a.first != b.first ? a.first < b.first : a.second > b.second; };
  std::priority_queue<Item, std::vector<Item>, decltype(cmp)> queue(cmp);
  inCut[0] = 1;
  uint64_t total = nodes[0].count();
  if (!nodes[0].leaf) queue.push({priority(0), 0});
  while (!queue.empty()) {
    const uint32_t i = queue.top().second;
    queue.pop();
    const NodeInfo& n = nodes[i];
    int64_t cost = -int64_t(n.count());
    for (uint32_t c = n.firstChild; c < n.firstChild + n.childCount; ++c)
      if (visible(c)) cost += int64_t(nodes[c].count());
    if (int64_t(total) + cost > int64_t(budget)) continue;  // stays coarse; smaller nodes may still fit
    total = uint64_t(int64_t(total) + cost);
    inCut[i] = 0;
    for (uint32_t c = n.firstChild; c < n.firstChild + n.childCount; ++c)
      if (visible(c)) {
        inCut[c] = 1;
        if (!nodes[c].leaf) queue.push({priority(c), c});
      }
  }
  for (uint32_t i = 0; i < nodes.size(); ++i)
    if (inCut[i]) sel.nodes.push_back(i);
  sel.primitives = total;
  return sel;
}

Assembled assemble(const LodFile& file, const Selection& selection, float radiusScale) {
  const LodHeader& h = file.header();
  const auto& nodes = file.nodes();
  const size_t n = selection.nodes.size();
  // Where each node's primitives go, from the table's counts: originals first, then the
  // representatives in node order. When every leaf is drawn the originals are placed by their
  // model index, so the model drawn is today's model; otherwise they keep node order
  // (deterministic, and no sort in the frame). Blocks are decoded straight into place.
  // A node whose block lies past the file's end gets no place, and the originals are placed by
  // index only when every leaf's block is in the file: no count sizes memory beyond the bytes
  // the file holds (its blocks do not overlap: validateHierarchy).
  uint64_t leafPoints = 0, leafSegments = 0, np = 0, ns = 0;
  bool reps = false, leafPastEnd = false;
  for (uint32_t i : selection.nodes) {
    if (!file.inFile(i)) {
      leafPastEnd |= nodes[i].leaf;
      continue;
    }
    np += nodes[i].points, ns += nodes[i].segments;
    if (nodes[i].leaf) leafPoints += nodes[i].points, leafSegments += nodes[i].segments;
    else reps = true;
  }
  const bool byIndex = !leafPastEnd && leafPoints == h.points && leafSegments == h.segments;
  std::vector<uint64_t> pointAt(n), segmentAt(n);
  uint64_t pl = 0, sl = 0, pr = leafPoints, sr = leafSegments;
  for (size_t k = 0; k < n; ++k) {
    const NodeInfo& nd = nodes[selection.nodes[k]];
    if (!file.inFile(selection.nodes[k])) continue;
    if (nd.leaf) pointAt[k] = pl, segmentAt[k] = sl, pl += nd.points, sl += nd.segments;
    else pointAt[k] = pr, segmentAt[k] = sr, pr += nd.points, sr += nd.segments;
  }
  Assembled out;
  HybridModel& m = out.model;
  m.attributes = h.attributes;
  if (reps) m.attributes.normals = m.attributes.radii = true;
  const bool withMasses = h.pointMasses || reps, shading = h.attributes.shadingNormals;
  m.points.resize(np);
  m.segments.resize(ns);
  std::vector<float> masses(withMasses ? np : 0);
  if (shading) m.pointShadingNormals.resize(np);
  std::vector<std::string> failed(n);
  parallelFor(0, n, [&](size_t k) {
    thread_local std::vector<char> buf;
    const uint32_t i = selection.nodes[k];
    const NodeInfo& nd = nodes[i];
    try {
      file.readBlock(i, buf);
    } catch (const Error& e) {
      failed[k] = e.what();
      return;
    }
    const bool place = nd.leaf && byIndex;
    const char* p = buf.data() + format::kBlockHeaderBytes;
    for (uint32_t j = 0; j < nd.points; ++j, p += format::kPointBytes) {
      Point pt;
      Vec3f sn;
      float mass;
      uint32_t idx;
      format::getPoint(p, pt, sn, mass, idx);
      const uint64_t at = place ? idx : pointAt[k] + j;
      pt.radius *= radiusScale;
      m.points[at] = pt;
      if (withMasses) masses[at] = mass;
      if (shading) m.pointShadingNormals[at] = sn;
    }
    for (uint32_t j = 0; j < nd.segments; ++j, p += format::kSegmentBytes) {
      Segment s;
      uint32_t idx;
      format::getSegment(p, s, idx);
      s.radius *= radiusScale;
      m.segments[place ? idx : segmentAt[k] + j] = s;
    }
  }, 1);
  // Failed nodes leave their places empty: drop them (a failed leaf read by index left the
  // places of its own primitives, known only from its intact neighbours: every place not written).
  bool anyFailed = false;
  for (size_t k = 0; k < n; ++k)
    if (!failed[k].empty()) out.failures.push_back(failed[k]), anyFailed = true;
    else if (!nodes[selection.nodes[k]].leaf) ++out.representativeNodes;
  if (anyFailed) {
    std::vector<char> keepP(np, 0), keepS(ns, 0);
    for (size_t k = 0; k < n; ++k) {
      if (!failed[k].empty()) continue;
      const NodeInfo& nd = nodes[selection.nodes[k]];
      if (nd.leaf && byIndex) {
        const NodeData d = file.readNode(selection.nodes[k]);  // rare path: the indices again
        for (uint32_t idx : d.pointIndex) keepP[idx] = 1;
        for (uint32_t idx : d.segmentIndex) keepS[idx] = 1;
      } else {
        std::fill_n(keepP.begin() + pointAt[k], nd.points, 1);
        std::fill_n(keepS.begin() + segmentAt[k], nd.segments, 1);
      }
    }
    size_t w = 0;
    for (size_t r = 0; r < np; ++r)
      if (keepP[r]) {
        m.points[w] = m.points[r];
        if (withMasses) masses[w] = masses[r];
        if (shading) m.pointShadingNormals[w] = m.pointShadingNormals[r];
        ++w;
      }
    m.points.resize(w);
    if (withMasses) masses.resize(w);
    if (shading) m.pointShadingNormals.resize(w);
    w = 0;
    for (size_t r = 0; r < ns; ++r)
      if (keepS[r]) m.segments[w++] = m.segments[r];
    m.segments.resize(w);
  }
  if (withMasses && !m.points.empty()) m.pointProperties[kPointMassProperty] = std::move(masses);
  return out;
}

LodRenderer::LodRenderer(const LodFile& file, const RenderOptions& options, uint64_t budget, float radiusScale)
    : file_(file), options_(options), budget_(budget), radiusScale_(radiusScale) {
  validate(options_);
}

BoundingSphere LodRenderer::sphere() const {
  BoundingSphere s = file_.header().sphere;
  if (radiusScale_ != 1) s.radius += (radiusScale_ - 1) * file_.header().maxRadius;
  return s;
}

LodFrameResult LodRenderer::render(const Camera& camera) const {
  LodFrameResult r;
  Timer t;
  r.selection = selectNodes(file_, camera, budget_);
  r.selectSeconds = t.seconds();
  Timer tl;
  Assembled a = assemble(file_, r.selection, radiusScale_);
  r.loadSeconds = tl.seconds();
  r.failures = std::move(a.failures);
  if (a.model.empty()) {  // every selected node failed: the background alone
    r.render.color = Image(camera.width(), camera.height(), options_.background);
    return r;
  }
  r.render = Renderer(a.model, options_).render(camera);
  return r;
}

}  // namespace linesurf::lod
