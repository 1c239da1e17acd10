// Lines of curvature traced on the MLS surface (thesis §9.2; see extract/curvature_lines.h).
#include "linesurf/extract/curvature_lines.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "detail/cross_field.h"
#include "detail/endpoint_normals.h"
#include "detail/segment_attributes.h"
#include "detail/segment_width.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/surface/mls.h"
#include "surface/detail/point_tree.h"

namespace linesurf {
namespace {

using Cloud = detail::PointCloud;
using Tree = detail::PointTree;

/// A sample of a traced line: on the surface, with its normal and direction.
struct Sample {
  Vec3d p;
  Vec3f n, t;
  float dsep;
  uint32_t line;
  float arc;  ///< signed arc length from the line's seed
};

/// Line samples by cell, for the separation test (cells of the largest d_sep).
class SampleGrid {
 public:
  explicit SampleGrid(double cell) : cell_(cell) {}
  void insert(const std::vector<Sample>& all, uint32_t index) { cells_[key(all[index].p)].push_back(index); }
  /// Whether a sample other than the current line's nearby ones lies within `radius` of x (with a
  /// direction within 45 degrees of t's line when `sameFamily`). Samples of `line` count only when
  /// their arc length differs from `arc` by more than `selfGap`.
  bool near(const std::vector<Sample>& all, const Vec3d& x, const Vec3f& t, double radius, bool sameFamily,
            uint32_t line, float arc, float selfGap) const {
    const int64_t cx = coord(x.x()), cy = coord(x.y()), cz = coord(x.z());
    const double r2 = radius * radius;
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          auto it = cells_.find(pack(cx + dx, cy + dy, cz + dz));
          if (it == cells_.end()) continue;
          for (uint32_t s : it->second) {
            const Sample& q = all[s];
            if ((q.p - x).squaredNorm() > r2) continue;
            if (q.line == line && std::abs(q.arc - arc) <= selfGap) continue;
            if (sameFamily && std::abs(q.t.dot(t)) < 0.7071f) continue;
            return true;
          }
        }
    return false;
  }

 private:
  // Clamped before the conversion (a float beyond int64 is undefined); cells wrap at 2^21 anyway.
  int64_t coord(double v) const { return int64_t(std::clamp(std::floor(v / cell_), -1e15, 1e15)); }
  static uint64_t pack(int64_t x, int64_t y, int64_t z) {
    return (uint64_t(x & 0x1FFFFF) << 42) | (uint64_t(y & 0x1FFFFF) << 21) | uint64_t(z & 0x1FFFFF);
  }
  uint64_t key(const Vec3d& p) const { return pack(coord(p.x()), coord(p.y()), coord(p.z())); }
  double cell_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

enum class Stop { Separation, Singularity, Boundary, Closed, Length };

/// The field and the surface at a point of space, from the nearest input points.
struct FieldSample {
  Vec3f dir = Vec3f::Zero();  ///< unit tangent, the cross axis nearest to the reference
  Vec3f normal = Vec3f::Zero();
  float coherence = 0;
  float across = 0;   ///< |normal curvature| across dir
  float nearest = 0;  ///< distance to the nearest input point over its spacing
  bool valid = false;
};

struct Tracer {
  const HybridModel& cloud;
  const PointGeometry& geo;
  const detail::CrossField& field;
  const MlsSurface& surface;
  const Tree& tree;
  const CurvatureLineOptions& o;
  double epsilon, spacing, step, dsepMax, dsepMin;
  bool sameFamilyOnly;
  std::vector<Sample> samples;
  SampleGrid grid;
  CurvatureLineStats& st;

  static constexpr int kNear = 8;

  FieldSample fieldAt(const Vec3d& x, const Vec3f& ref) const {
    FieldSample f;
    uint32_t idx[kNear];
    float d2[kNear];
    const float q[3] = {float(x.x()), float(x.y()), float(x.z())};
    const size_t found = tree.knnSearch(q, kNear, idx, d2);
    if (found == 0) return f;
    f.nearest = std::sqrt(d2[0]) / std::max(geo.spacing[idx[0]], 1e-30f);
    const float support = 1.01f * std::sqrt(d2[found - 1]) + 1e-30f;
    Vec3f v = Vec3f::Zero(), nrm = Vec3f::Zero();
    float wsum = 0, across = 0;
    for (size_t m = 0; m < found; ++m) {
      const uint32_t j = idx[m];
      const float u = 1.0f - d2[m] / (support * support);
      const float w = u * u + 1e-6f;
      const Vec3f a = detail::nearestAxis(field.axis[j], field.normal[j], ref);
      v += w * a;
      nrm += w * field.normal[j];
      // Normal curvature across a (along normal x a): k_max cos^2 + k_min sin^2 of its angle to
      // the maximum direction, i.e. to normal x minDir.
      const Vec3f side = field.normal[j].cross(a);
      const float c = side.dot(field.minDir[j]);
      across += w * std::abs(field.kMax[j] * (1 - c * c) + field.kMin[j] * c * c);
      wsum += w;
    }
    f.coherence = v.norm() / wsum;
    nrm.normalize();
    v -= v.dot(nrm) * nrm;
    const float len = v.norm();
    if (!(len > 1e-6f) || !nrm.allFinite()) return f;
    f.dir = v / len;
    f.normal = nrm;
    f.across = across / wsum;
    f.valid = true;
    return f;
  }

  /// d_sep where the normal curvature across the line is `across`: the strip of half-width
  /// widthScale d_sep / 2 bends away from its plane by across r^2 / 2 <= epsilon.
  double separationFor(float across) const {
    double d = dsepMax;
    if (across > 0) d = std::min(d, 2.0 * std::sqrt(2.0 * epsilon / double(across)) / o.widthScale);
    return std::max(d, dsepMin);
  }

  /// Appends a sample on the surface at p (its normal `n` turned to the side of the field's
  /// `side`) to the samples and the grid; its index.
  uint32_t addSample(const Vec3d& p, Vec3f n, const Vec3f& side, const Vec3f& t, double dsep, uint32_t line, float arc) {
    if (n.dot(side) < 0) n = -n;
    samples.push_back({p, n, t, float(dsep), line, arc});
    const uint32_t id = uint32_t(samples.size() - 1);
    grid.insert(samples, id);
    return id;
  }

  /// Traces from the seed (already sample `seed`) in direction dir; appends samples.
  Stop trace(uint32_t line, uint32_t seed, Vec3f dir, float sign, std::vector<uint32_t>& out) {
    Vec3d x = samples[seed].p;
    Vec3f t = dir;
    float arc = 0;
    const size_t maxSteps = size_t(4.0 * double(cloud.points.size()) + 1000);
    for (size_t s = 0; s < maxSteps; ++s) {
      auto F = [&](const Vec3d& at, const Vec3f& ref, FieldSample& fs) {
        fs = fieldAt(at, ref);
        return fs.valid;
      };
      FieldSample f1, f2, f3, f4;
      const double h = step;
      if (!F(x, t, f1) || f1.coherence < 0.5f) return Stop::Singularity;
      if (!F(x + 0.5 * h * f1.dir.cast<double>(), f1.dir, f2)) return Stop::Singularity;
      if (!F(x + 0.5 * h * f2.dir.cast<double>(), f2.dir, f3)) return Stop::Singularity;
      if (!F(x + h * f3.dir.cast<double>(), f3.dir, f4)) return Stop::Singularity;
      Vec3f v = (f1.dir + 2 * f2.dir + 2 * f3.dir + f4.dir) / 6.0f;
      if (!(v.norm() > 0.5f)) return Stop::Singularity;  // the four stages disagree: a turn too sharp
      v.normalize();
      const Vec3d predicted = x + h * v.cast<double>();
      const MlsProjection pr = surface.project(predicted);
      ++st.steps;
      if (!pr.converged) {
        ++st.projectionFailures;
        return Stop::Boundary;
      }
      if ((pr.point - predicted).norm() > h) return Stop::Boundary;
      const Vec3d moved = pr.point - x;
      if (!(moved.norm() > 1e-3 * h)) return Stop::Singularity;
      const Vec3f tNew = moved.normalized().cast<float>();
      if (tNew.dot(t) < 0.7071f) return Stop::Singularity;
      const FieldSample here = fieldAt(pr.point, tNew);
      if (!here.valid || here.nearest > 2.0f) return Stop::Boundary;
      arc += sign * float(moved.norm());
      const double dsep = separationFor(here.across);
      // Closing on itself: back at the seed after going round.
      if (std::abs(arc) > 2 * dsep && (pr.point - samples[out.front()].p).norm() < 1.5 * h) return Stop::Closed;
      if (grid.near(samples, pr.point, tNew, 0.5 * dsep, sameFamilyOnly, line, arc, float(3 * dsep))) return Stop::Separation;
      out.push_back(addSample(pr.point, pr.normal.cast<float>(), here.normal, tNew, dsep, line, arc));
      x = pr.point;
      t = tNew;
    }
    return Stop::Length;
  }

  void count(Stop s) {
    switch (s) {
      case Stop::Separation: ++st.stopSeparation; break;
      case Stop::Singularity: ++st.stopSingularity; break;
      case Stop::Boundary: ++st.stopBoundary; break;
      case Stop::Closed: ++st.stopClosed; break;
      case Stop::Length: ++st.stopLength; break;
    }
  }
};

/// A traced line: sample indices in order along it.
struct Line {
  std::vector<uint32_t> ids;
  bool closed = false;
  double length = 0;
  double dsep = 0;  ///< mean d_sep along it
};

/// §9.2 step 2: evenly spaced lines, placed one after another (Jobard & Lefer 1997).
std::vector<Line> placeLines(Tracer& tr) {
  const CurvatureLineOptions& o = tr.o;
  const double s = tr.spacing;
  std::vector<Line> lines;
  double dsepSum = 0;
  size_t dsepCount = 0;
  // Tries a seed at x (projected onto the surface) along the cross axis nearest to `ref`.
  auto trySeed = [&](const Vec3d& x, const Vec3f* ref, bool useMax, double dsepHint) -> bool {
    // Most candidates lie near a line already: ask the grid before projecting.
    if (tr.grid.near(tr.samples, x, ref ? *ref : Vec3f::Zero(), 0.9 * dsepHint, tr.sameFamilyOnly && ref, UINT32_MAX, 0, 0))
      return false;
    const MlsProjection pr = tr.surface.project(x);
    if (!pr.converged) return false;
    Vec3f r;
    if (ref) {
      r = *ref;
    } else {
      uint32_t idx;
      float d2;
      const float q[3] = {float(pr.point.x()), float(pr.point.y()), float(pr.point.z())};
      tr.tree.knnSearch(q, 1, &idx, &d2);
      r = tr.field.minDir[idx];
      if (r == Vec3f::Zero()) r = tr.field.axis[idx];
      if (useMax) r = tr.field.normal[idx].cross(r);
    }
    const FieldSample f = tr.fieldAt(pr.point, r);
    if (!f.valid || f.nearest > 2.0f || f.coherence < 0.5f) return false;
    const double dsep = tr.separationFor(f.across);
    const uint32_t lineId = uint32_t(lines.size());
    if (tr.grid.near(tr.samples, pr.point, f.dir, dsep, tr.sameFamilyOnly, UINT32_MAX, 0, 0)) return false;
    const uint32_t seed = tr.addSample(pr.point, pr.normal.cast<float>(), f.normal, f.dir, dsep, lineId, 0);
    std::vector<uint32_t> fwd{seed}, bwd{seed};
    const Stop a = tr.trace(lineId, seed, f.dir, 1.0f, fwd);
    tr.count(a);
    Line ln;
    if (a == Stop::Closed) {
      ln.closed = true;
      ++tr.st.stopClosed;  // both ends
      ln.ids = fwd;
      ln.ids.push_back(seed);  // bit-equal: the chain closes on its first endpoint
    } else {
      const Stop b = tr.trace(lineId, seed, Vec3f(-f.dir), -1.0f, bwd);
      tr.count(b);
      ln.ids.assign(bwd.rbegin(), bwd.rend());
      ln.ids.insert(ln.ids.end(), fwd.begin() + 1, fwd.end());
    }
    for (size_t k = 1; k < ln.ids.size(); ++k) ln.length += (tr.samples[ln.ids[k]].p - tr.samples[ln.ids[k - 1]].p).norm();
    double ds = 0;
    for (uint32_t id : ln.ids) ds += tr.samples[id].dsep;
    ln.dsep = ds / double(ln.ids.size());
    dsepSum += dsep, ++dsepCount;
    lines.push_back(std::move(ln));
    return true;
  };
  const int passes = o.family == CurvatureFamily::Both ? 2 : 1;
  size_t lastReport = 0;
  for (int pass = 0; pass < passes; ++pass) {
    const bool useMax = o.family == CurvatureFamily::Max || pass == 1;
    size_t scan = 0;
    size_t queued = lines.size();
    while (true) {
      // Seeds at d_sep either side of every accepted line, in the order the lines came.
      while (queued < lines.size()) {
        const Line ln = lines[queued++];  // a copy: trySeed appends to `lines`
        size_t stride = 1;
        for (size_t k = 0; k < ln.ids.size(); k += stride) {
          const Sample smp = tr.samples[ln.ids[k]];
          stride = std::max<size_t>(1, size_t(std::lround(0.5 * smp.dsep / tr.step)));
          const Vec3f side = smp.n.cross(smp.t).normalized();
          for (float sgn : {1.0f, -1.0f}) trySeed(smp.p + double(sgn * smp.dsep) * side.cast<double>(), &smp.t, useMax, smp.dsep);
        }
        if (lines.size() - lastReport >= 64) {
          lastReport = lines.size();
          reportProgress(o.progress, "trace", std::min(0.99, double(tr.samples.size()) * tr.step * s / (double(tr.cloud.points.size()) * s * s)));
        }
      }
      // A new component (or a gap no neighbour seed reached): the next input point, in order,
      // at least d_sep from every line.
      bool seeded = false;
      for (; scan < tr.cloud.points.size() && !seeded; ++scan) {
        if (tr.geo.flags[scan] & (kPointIsolated | kPointDuplicate)) continue;
        seeded = trySeed(tr.cloud.points[scan].position.cast<double>(), nullptr, useMax, tr.dsepMin);
      }
      if (!seeded) break;
    }
  }
  tr.st.meanSeparation = dsepCount ? dsepSum / double(dsepCount) : 0.0;
  return lines;

}

/// §9.2 step 3: each line straightened into a chain of chords under §3.1's epsilon and delta.
std::vector<Segment> straighten(const Tracer& tr, const std::vector<Line>& lines, CurvatureLineStats& st) {
  const CurvatureLineOptions& o = tr.o;
  std::vector<Segment> segments;
  const float cosLimit = float(1.0 - o.delta);
  for (size_t li = 0; li < lines.size(); ++li) {
    const Line& ln = lines[li];
    if (ln.ids.size() < 2 || ln.length < o.minLength * ln.dsep) {
      ++st.prunedLines;
      continue;
    }
    const size_t first = segments.size();
    size_t a = 0;
    const size_t m = ln.ids.size();
    while (a + 1 < m) {
      size_t b = a + 1;
      // Extend b while the chord a..b+1 holds every sample between within epsilon and delta.
      while (b + 1 < m && b + 1 - a <= 512) {
        const size_t c = b + 1;
        const Vec3d pa = tr.samples[ln.ids[a]].p, pc = tr.samples[ln.ids[c]].p;
        const Vec3d d = pc - pa;
        const double len2 = d.squaredNorm();
        if (!(len2 > 0)) break;
        Vec3f nsum = Vec3f::Zero();
        for (size_t k = a; k <= c; ++k) nsum += tr.samples[ln.ids[k]].n;
        Vec3d nc = nsum.cast<double>();
        nc -= nc.dot(d) / len2 * d;
        if (!(nc.norm() > 1e-9)) break;
        nc.normalize();
        // §3.1's epsilon bounds the distance to the surface: the samples' offset from the strip's
        // plane. Their sideways drift within the plane moves the strip over the surface, not off
        // it; a tenth of the strip's half-width keeps its cover.
        double lateralLimit = 1e300;
        for (size_t k = a; k <= c; ++k) lateralLimit = std::min(lateralLimit, 0.05 * o.widthScale * tr.samples[ln.ids[k]].dsep);
        bool ok = true;
        for (size_t k = a + 1; k < c && ok; ++k) {
          const Vec3d r = tr.samples[ln.ids[k]].p - pa;
          const Vec3d off = r - r.dot(d) / len2 * d;
          const double normal = std::abs(off.dot(nc));
          ok = normal <= st.epsilon && (off - off.dot(nc) * nc).norm() <= lateralLimit;
        }
        for (size_t k = a; k <= c && ok; ++k) ok = tr.samples[ln.ids[k]].n.cast<double>().dot(nc) >= cosLimit;
        if (!ok) break;
        b = c;
      }
      const Sample& sa = tr.samples[ln.ids[a]];
      const Sample& sb = tr.samples[ln.ids[b]];
      Segment sg;
      sg.p0 = sa.p.cast<float>(), sg.p1 = sb.p.cast<float>();
      // Consecutive chords share a sample, so their float endpoints are bit-equal.
      Vec3f nsum = Vec3f::Zero();
      float dsum = 0;
      for (size_t k = a; k <= b; ++k) nsum += tr.samples[ln.ids[k]].n, dsum += tr.samples[ln.ids[k]].dsep;
      sg.normal = nsum;
      const Vec3f dir = sg.p1 - sg.p0;
      if (dir.squaredNorm() > 0) sg.normal -= sg.normal.dot(dir) / dir.squaredNorm() * dir;
      sg.normal.normalize();
      if (!sg.normal.allFinite()) sg.normal = sa.n;
      detail::setEndpointNormals(sg, sa.n, sb.n);
      sg.radius = float(0.5 * o.widthScale * dsum / float(b - a + 1));
      if (sg.p0 != sg.p1) {
        segments.push_back(sg);
      }
      a = b;
    }
    if (segments.size() > first) {
      ++st.lines;
      st.closedLines += ln.closed;
      st.lineLength += ln.length;
      if (ln.length < 2 * ln.dsep) ++st.shortLines, st.shortLength += ln.length;
    }
  }

  return segments;
}

/// §9.2 step 4: each input point within a strip goes to the nearest such strip (its index), the
/// rest stay points (-1).
std::vector<int64_t> coverPoints(const HybridModel& cloud, const MlsSurface& surface, const std::vector<Segment>& segments,
                                 double epsilon) {
  const size_t n = cloud.points.size();
  Cloud mids;
  double reach = 0;
  for (const Segment& sg : segments) {
    mids.pts.push_back(0.5f * (sg.p0 + sg.p1));
    reach = std::max(reach, 0.5 * double(sg.length()) + double(sg.radius));
  }
  std::vector<int64_t> owner(n, -1);
  if (!segments.empty()) {
    Tree segTree(3, mids, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    segTree.buildIndex();
    parallelFor(0, n, [&](size_t i) {
      const Vec3d q = cloud.points[i].position.cast<double>();
      thread_local std::vector<std::pair<uint32_t, float>> found;
      found.clear();
      const float qq[3] = {float(q.x()), float(q.y()), float(q.z())};
      nanoflann::SearchParams params;
      params.sorted = false;
      segTree.radiusSearch(qq, float(reach * reach), found, params);
      if (found.empty()) return;
      const MlsSample fs = surface.evaluate(q, false);
      const double off = fs.valid() ? std::abs(fs.value) : 0.0;
      double best = 1e300;
      int64_t bestSeg = -1;
      for (const auto& [j, unused] : found) {
        const Segment& sg = segments[j];
        const Vec3d p0 = sg.p0.cast<double>(), d = (sg.p1 - sg.p0).cast<double>();
        const double t = std::clamp((q - p0).dot(d) / d.squaredNorm(), 0.0, 1.0);
        const Vec3d r = q - (p0 + t * d);
        const Vec3d nn = sg.normal.cast<double>();
        const double plane = std::abs(r.dot(nn));
        const double lateral = (r - r.dot(nn) * nn).norm();
        // The strip stands within epsilon of the surface along its chord and within epsilon
        // across its width; the point adds its own distance to the surface.
        if (lateral > double(sg.radius) || plane > 2 * epsilon + off) continue;
        if (lateral < best || (lateral == best && int64_t(j) < bestSeg)) best = lateral, bestSeg = int64_t(j);
      }
      owner[i] = bestSeg;
    });
  }

  return owner;
}

/// The output: kept points in input order, then the chains.
HybridModel assemble(const HybridModel& cloud, const HybridModel& base, const std::vector<Segment>& segments,
                     const std::vector<int64_t>& owner, bool provenance) {
  const size_t n = cloud.points.size();
  HybridModel out;
  out.attributes = base.attributes;
  out.attributes.endpointNormals = true;
  out.comments = base.comments;
  out.texture = cloud.texture;
  for (const auto& [name, values] : base.pointProperties) out.pointProperties[name];
  std::vector<Eigen::Vector4d> colorSum(segments.size(), Eigen::Vector4d::Zero());
  std::vector<uint32_t> members(segments.size(), 0);
  if (provenance) out.provenance.assign(segments.size(), {});
  for (size_t i = 0; i < n; ++i) {
    if (owner[i] < 0) {
      out.points.push_back(base.points[i]);
      for (const auto& [name, values] : base.pointProperties)
        if (values.size() == n) out.pointProperties[name].push_back(values[i]);
      if (base.attributes.shadingNormals && cloud.pointShadingNormals.size() == n)
        out.pointShadingNormals.push_back(cloud.pointShadingNormals[i]);
      continue;
    }
    const size_t j = size_t(owner[i]);
    const Color& c = cloud.points[i].color;
    colorSum[j] += c.cast<double>();
    ++members[j];
    if (provenance) out.provenance[j].push_back(uint32_t(i));
  }
  for (auto it = out.pointProperties.begin(); it != out.pointProperties.end();)
    it = it->second.size() == out.points.size() ? std::next(it) : out.pointProperties.erase(it);
  if (out.pointShadingNormals.size() != out.points.size()) {
    out.pointShadingNormals.clear();
    out.attributes.shadingNormals = false;
  }
  for (size_t j = 0; j < segments.size(); ++j) {
    Segment sg = segments[j];
    if (members[j] > 0) {
      sg.color = (colorSum[j] / double(members[j])).cast<float>();
    }
    out.segments.push_back(sg);
  }
  std::vector<uint32_t> own(n);
  for (size_t i = 0; i < n; ++i) own[i] = owner[i] < 0 ? detail::kKeptPoint : uint32_t(owner[i]);
  detail::setSegmentProperties(out, base, own);
  return out;
}

}  // namespace

void validate(const CurvatureLineOptions& o) {
  if (!(o.epsilon >= 0 && o.epsilon <= 1e30))
    throwBadOption("epsilon", "must be a finite distance in [0, 1e30] (0 = use `epsilonRelative`), got " + numberText(o.epsilon));
  if (o.epsilon == 0 && !(o.epsilonRelative > 0 && o.epsilonRelative <= 1e6))
    throwBadOption("epsilonRelative", "must be a fraction of the average spacing in (0, 1e6], got " + numberText(o.epsilonRelative));
  if (!(o.delta >= 0 && o.delta <= 2)) throwBadOption("delta", "must lie in [0, 2] (it bounds 1 - n_i.n_j), got " + numberText(o.delta));
  requireRange("separation", o.separation, 1, 100, "average spacings");
  requireRange("minSeparation", o.minSeparation, 0.25, o.separation, "average spacings (at most `separation`)");
  requireRange("widthScale", o.widthScale, 1, 3);
  if (!(o.step > 0 && o.step <= 4)) throwBadOption("step", "must lie in (0, 4] average spacings, got " + numberText(o.step));
  requireRange("minLength", o.minLength, 0, 100, "d_sep");
  requireRange("smoothingIterations", o.smoothingIterations, 0, 1000);
  requireRange("fieldDataWeight", o.fieldDataWeight, 0, 1e6);
  requireRange("supportScale", o.supportScale, 1.5, 10, "spacings");
}

HybridModel extractCurvatureLines(const HybridModel& cloud, const PointGeometry& geo, const CurvatureLineOptions& o,
                                  CurvatureLineStats* statsOut) {
  validate(o);
  const size_t n = cloud.points.size();
  const bool graph = geo.neighbours.size() == n * size_t(geo.k) || geo.delaunayOffsets.size() == n + 1;
  if (geo.size() != n || geo.spacing.size() != n || geo.flags.size() != n || !graph)
    throwBadParameter("geometry", "does not match the cloud (computePointGeometry with normals, neighbours and spacing)");
  CurvatureLineStats st;
  st.inputPoints = n;
  st.averageSpacing = geo.averageSpacing;
  st.epsilon = o.epsilon > 0 ? o.epsilon : o.epsilonRelative * double(geo.averageSpacing);
  st.delta = o.delta;

  HybridModel base;
  base.points = cloud.points;
  base.attributes = cloud.attributes;
  base.pointProperties = cloud.pointProperties;
  base.comments = cloud.comments;
  for (size_t i = 0; i < n; ++i) {
    base.points[i].normal = geo.normals[i];
    if (!(base.points[i].radius > 0))
      base.points[i].radius = !geo.coverRadius.empty() && geo.coverRadius[i] > 0 ? geo.coverRadius[i] : geo.spacing[i];
  }
  base.attributes.normals = base.attributes.radii = true;
  base.comments.push_back(fmt::format("curvature-lines: epsilon={:.9g} delta={:.9g} separation={:.9g} family={}", st.epsilon, o.delta,
                                      o.separation, o.family == CurvatureFamily::Min ? "min" : o.family == CurvatureFamily::Max ? "max" : "both"));
  auto allPoints = [&] {
    st.keptPoints = n;
    if (statsOut) *statsOut = st;
    return base;
  };
  // A cloud without a surface: too few points for a neighbourhood, or flat neighbourhoods
  // (collinear) for most points. Documented result: every point kept.
  size_t flat = 0;
  for (uint8_t fl : geo.flags) flat += (fl & (kPointFlatNeighbourhood | kPointFewNeighbours)) != 0;
  if (n < 16 || !(geo.averageSpacing > 0) || flat * 2 > n) return allPoints();

  // Step 1: the surface and the cross field.
  Timer timer;
  MlsOptions mo;
  mo.supportScale = o.supportScale;
  const MlsSurface surface(base, mo);
  const detail::CrossField field = detail::computeCrossField(base, geo, surface, o.smoothingIterations, o.fieldDataWeight);
  Cloud pts;
  pts.pts.resize(n);
  for (size_t i = 0; i < n; ++i) pts.pts[i] = cloud.points[i].position;
  Tree tree(3, pts, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  st.fieldSeconds = timer.seconds();
  reportProgress(o.progress, "field", 1.0);

  // Step 2: evenly spaced lines, placed one after another (Jobard & Lefer 1997).
  timer.reset();
  const double s = geo.averageSpacing;
  Tracer tr{cloud, geo, field, surface, tree, o, st.epsilon, s, o.step * s, o.separation * s, o.minSeparation * s,
            o.family == CurvatureFamily::Both, {}, SampleGrid(o.separation * s), st};
  const std::vector<Line> lines = placeLines(tr);
  st.traceSeconds = timer.seconds();
  reportProgress(o.progress, "trace", 1.0);
  timer.reset();
  const std::vector<Segment> segments = straighten(tr, lines, st);
  st.straightenSeconds = timer.seconds();
  timer.reset();
  const std::vector<int64_t> owner = coverPoints(cloud, surface, segments, st.epsilon);
  st.coverSeconds = timer.seconds();
  HybridModel out = assemble(cloud, base, segments, owner, o.provenance);
  reportProgress(o.progress, "cover", 1.0);
  st.keptPoints = out.points.size();
  st.replacedPoints = n - st.keptPoints;
  st.segments = out.segments.size();
  reportProgress(o.progress, "cover", 1.0);
  if (statsOut) *statsOut = st;
  return out;
}

}  // namespace linesurf
