// The prepare stage of segment splats in batches (segment_setup.h): the frame's constants of the
// SIMD set-up, and the batches around it, which hand every lane the set-up cannot decide safely to
// the exact path (prepareSegment, segment_splat.cpp; see docs/decisions.md, "Segment prepare").
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <new>

#include "point_setup.h"
#include "segment_setup.h"
#include "splat_rules.h"

namespace linesurf {

detail::SegmentSetupFrame segmentSetupFrame(const FrameContext& frame) {
  const RenderOptions& opt = frame.opt();
  detail::SegmentSetupFrame f;
  f.view = pointSetupFrame(frame);  // the camera, filter and material constants points use
  f.invF = 1 / f.view.f;
  f.reach = float(double(opt.cutoffRadius) * opt.reconstructionScale * detail::kMaxStretch);
  f.smoothFrame = frame.endpointNormals;
  f.modelColors = frame.modelHasColors;
  for (int c = 0; c < 4; ++c) f.defaultColor[c] = opt.defaultColor[c];
  f.alphaOverride = opt.alphaOverride >= 0 ? opt.alphaOverride : -1.0f;
  f.perPixelLighting = opt.perPixelLighting;
  f.specularTable = frame.specularPow ? frame.specularPow->data() : nullptr;
  f.light = !opt.perPixelLighting && (f.specularTable || !(opt.material.specular > 0));
  for (int c = 0; c < 3; ++c) f.lightColor[c] = opt.light.color[c];
  f.z = frame.zRule;
  // the common case the SIMD code handles: the ScreenSpace method, untextured, with a prefilter
  f.simd = opt.segmentMethod == SegmentMethod::ScreenSpace && !frame.texture && opt.prefilterVariance > 0;
  // the record words every common-case segment shares (as prepareSegment writes them for it);
  // padding zero
  alignas(PreparedSegment) unsigned char bytes[sizeof(PreparedSegment)] = {};
  PreparedSegment* t = new (bytes) PreparedSegment;
  t->method = SegmentMethod::ScreenSpace;
  t->fallback = false;
  t->useSpans = true;
  t->shade = SegmentShade::Linear;
  detail::SegmentRaster& k = t->raster;
  k.R2 = frame.cutoffQ;
  k.nearD = f.view.nearD, k.farD = f.view.farD;
  k.clipDepth = false;
  k.pieceCount = 1;
  k.pieces = nullptr;
  k.pieceInvLength = 0, k.pieceMaxReach = 0;
  t->attr[Z3Tile::kW] = 1.0f;
  std::memcpy(f.record.word, bytes + detail::kRecordBegin, sizeof(f.record.word));
  t->~PreparedSegment();
  return f;
}

namespace {

// The colours of a turning lane's stations + 1 lighting stations (prepareSegment's stage 6):
// the ends from the batch's Phong factors, the stations between them as segmentSetup lit them
// (F.light); else every station by FrameContext::shade.
void stationColours(const detail::SegmentSetupBatch& b, int j, const FrameContext& frame,
                    const detail::SegmentSetupFrame& F, int stations, float* colour) {
  const int n = stations + 1;
  if (F.light) {
    for (int c = 0; c < 3; ++c) {
      const float albedo = c == 0 ? b.cr[j] : c == 1 ? b.cg[j] : b.cb[j];
      colour[c * n] = (albedo * b.diffuse0[j] + b.specular0[j]) * F.lightColor[c];
      colour[c * n + stations] = (albedo * b.diffuse1[j] + b.specular1[j]) * F.lightColor[c];
    }
    const int at = b.stationJob[j] - 1;
    for (int s = 1; s < stations; ++s)
      colour[s] = b.stationR[at + s], colour[n + s] = b.stationG[at + s], colour[2 * n + s] = b.stationB[at + s];
    return;
  }
  const Vec3f p0(b.p0x[j], b.p0y[j], b.p0z[j]), p1(b.p1cx[j], b.p1cy[j], b.p1cz[j]);
  const Vec3f n0(b.n0x[j], b.n0y[j], b.n0z[j]), dn(b.dnx[j], b.dny[j], b.dnz[j]), albedo(b.cr[j], b.cg[j], b.cb[j]);
  for (int s = 0; s <= stations; ++s) {
    const float u = float(s) / float(stations);
    const Vec3f m = n0 + u * dn;
    const Vec3f c = frame.shade(albedo, m / m.norm(), p0 + u * (p1 - p0));
    for (int ch = 0; ch < 3; ++ch) colour[ch * n + s] = c[ch];
  }
}

}  // namespace

size_t prepareSegments(const Segment* segments, uint32_t first, size_t count, const FrameContext& frame,
                       const detail::SegmentSetupFrame& F, PreparedSegment* out, PrimitiveStatus* status) {
  if (!F.simd) {
    for (size_t j = 0; j < count; ++j) status[j] = prepareSegment(segments[first + j], uint32_t(first + j), frame, out[j]);
    return count;
  }
  size_t scalar = 0;
  detail::SegmentSetupBatch b;
  for (size_t base = 0; base < count; base += detail::kSegmentBatch) {
    const int n = int(std::min<size_t>(detail::kSegmentBatch, count - base));
    const bool loaded = detail::segmentLoad(F, b, segments + first + base, n, out + base);
    for (int j = 0; j < n && !loaded; ++j) {  // AoS -> SoA
      const Segment& s = segments[first + base + size_t(j)];
      // the input a batch ahead, every line it spans (a hint: an address past the array is harmless)
      const uintptr_t next = reinterpret_cast<uintptr_t>(&s) + detail::kSegmentBatch * sizeof(Segment);
      __builtin_prefetch(reinterpret_cast<const void*>(next));
      __builtin_prefetch(reinterpret_cast<const void*>(next + 64));
      __builtin_prefetch(reinterpret_cast<const void*>(next + sizeof(Segment) - 1));
      b.p0x[j] = s.p0.x(), b.p0y[j] = s.p0.y(), b.p0z[j] = s.p0.z();
      b.p1x[j] = s.p1.x(), b.p1y[j] = s.p1.y(), b.p1z[j] = s.p1.z();
      b.wx[j] = s.normal.x(), b.wy[j] = s.normal.y(), b.wz[j] = s.normal.z();
      b.radius[j] = s.radius;
      if (F.smoothFrame) {
        b.m0x[j] = s.normal0.x(), b.m0y[j] = s.normal0.y(), b.m0z[j] = s.normal0.z();
        b.m1x[j] = s.normal1.x(), b.m1y[j] = s.normal1.y(), b.m1z[j] = s.normal1.z();
      }
      // the lane's record slot, all its lines, into L2 unless the plane clearly faces away (the
      // records stream through memory once per frame; fetched a few lanes
      // before their writing, the writes stalled; from here the batch's set-up passes meanwhile)
      const Vec3f toEye = Vec3f(F.view.eye[0], F.view.eye[1], F.view.eye[2]) - s.p0;
      if (!(F.view.backfaceCulling && s.normal.dot(toEye) < 0)) {
        const char* slot = reinterpret_cast<const char*>(out + base + size_t(j));
        for (size_t o = 0; o < sizeof(PreparedSegment); o += 64) __builtin_prefetch(slot + o, 0, 2);
      }
      const Color col = frame.primitiveColor(s.color);
      b.cr[j] = col.x(), b.cg[j] = col.y(), b.cb[j] = col.z(), b.ca[j] = col.w();
    }
    for (int j = n; j < detail::kSegmentBatch && j < ((n + 15) & ~15); ++j) {  // harmless padding lanes
      b.p0x[j] = b.p0y[j] = b.p0z[j] = b.p1y[j] = b.p1z[j] = b.wx[j] = b.wy[j] = 0;
      b.p1x[j] = b.wz[j] = b.radius[j] = 1;
      b.smooth[j] = 0;
      b.m0x[j] = b.m0y[j] = b.m1x[j] = b.m1y[j] = 0;
      b.m0z[j] = b.m1z[j] = 1;
      b.cr[j] = b.cg[j] = b.cb[j] = b.ca[j] = 0;
    }
    b.first = uint32_t(first + base);
    detail::segmentToCamera(F, b, n);
    const int m = detail::segmentCull(F, b, n);  // lanes [0, m): b.lane[k] of [0, n), not decided yet
    // the lanes stage 1 decided (the others' bytes are written again below)
    std::memcpy(status + base, b.decidedStatus, size_t(n));
    for (uint64_t bits = b.exactLanes; bits; bits &= bits - 1) {
      const size_t i = base + size_t(std::countr_zero(bits));
      const uint32_t index = uint32_t(first + i);
      status[i] = prepareSegment(segments[index], index, frame, out[i]);
      ++scalar;
    }
    if (m == 0) continue;
    // the SegmentExtras kept in the survivors' slots (turning lanes whose stations do not fit the
    // record, and lanes with sub-segments, keep theirs from frame to frame: which lanes these are
    // does not depend on the view), fetched before the set-up: they missed the cache in the
    // writes below (see docs/decisions.md, "Segment prepare")
    for (int k = 0; k < m; ++k)
      if (const SegmentExtra* x = out[base + size_t(b.lane[k])].extra.get()) {
        const char* c = reinterpret_cast<const char*>(&x->colour);
        __builtin_prefetch(x, 1);
        __builtin_prefetch(c, 1);
        __builtin_prefetch(c + sizeof(x->colour) + 2 * sizeof(Vec2f) + 2 * sizeof(int), 1);
      }
    b.stationJobs = 0;
    detail::segmentSetup(F, b, m);
    detail::segmentRecords(F, b, m);
    for (int k = 0; k < m; ++k) {
      const size_t i = base + size_t(b.lane[k]);
      const uint32_t index = uint32_t(first + i);
      switch (int(b.status[k])) {
        case 0: status[i] = PrimitiveStatus::Drawn; break;
        case 1: status[i] = PrimitiveStatus::Culled; continue;
        case 3: status[i] = PrimitiveStatus::Clipped; break;
        case 4: status[i] = PrimitiveStatus::Outside; continue;
        default:
          status[i] = prepareSegment(segments[index], index, frame, out[i]);
          ++scalar;
          continue;
      }
      // the lane's record image (all but `extra`, which the common case neither reads nor resets)
      PreparedSegment& rec = out[i];
      char* dst = reinterpret_cast<char*>(&rec);
      std::memcpy(dst + 8, b.rec[0] + 4 * k + 2, 8);
      for (int c = 1; c < detail::kRecordChunks; ++c) std::memcpy(dst + 16 * c, b.rec[c] + 4 * k, 16);
      if (const int K = int(b.pieceCount[k]); K > 1) {  // its sub-segments in the slot's SegmentExtra
        SegmentExtra& x = extraOf(rec);
        x.pieces.resize(size_t(K));
        for (int p = 0; p < K; ++p) {
          auto f = [&](int field) { return b.piece[field][p][k]; };
          SegmentPiece& q = x.pieces[size_t(p)];
          q.a0 = f(detail::kPieceA0), q.a1 = f(detail::kPieceA1);
          q.m00 = f(detail::kPieceM00), q.m01 = f(detail::kPieceM01), q.m11 = f(detail::kPieceM11);
          q.scale0 = f(detail::kPieceScale0), q.scale1 = f(detail::kPieceScale1), q.reach = f(detail::kPieceReach);
          q.skew = f(detail::kPieceSkew), q.across = f(detail::kPieceAcross), q.invM00 = f(detail::kPieceInvM00);
          q.k = f(detail::kPieceK), q.erfScale = f(detail::kPieceErfScale), q.slope = f(detail::kPieceSlope);
        }
        x.pieceInvLength = b.pieceInvLength[k], x.pieceMaxReach = b.pieceMaxReach[k];
        detail::SegmentRaster& r = rec.raster;
        r.pieceCount = K, r.pieces = x.pieces.data();
        r.pieceInvLength = x.pieceInvLength, r.pieceMaxReach = x.pieceMaxReach;
      }
      const int stations = int(b.stations[k]);
      if (stations >= 0) {  // turning: shade Stations (in the record or SegmentExtra), lit at the stations
        float* colour = untexturedStations(rec, segments[index], stations);
        if (stations > 0) stationColours(b, k, frame, F, stations, colour);
      } else if (!F.light && !F.perPixelLighting) {  // Gouraud between the ends, lit per lane
        const Vec3f albedo(b.cr[k], b.cg[k], b.cb[k]);
        const Vec3f n1 = rec.n0 + rec.dn;
        const Vec3f k0 = frame.shade(albedo, rec.n0, Vec3f(b.p0x[k], b.p0y[k], b.p0z[k]));
        const Vec3f k1 = frame.shade(albedo, n1, Vec3f(b.p1cx[k], b.p1cy[k], b.p1cz[k]));
        float* a = rec.attr;
        a[Z3Tile::kR] = k0.x(), a[Z3Tile::kG] = k0.y(), a[Z3Tile::kB] = k0.z();
        rec.dc = k1 - k0;
      }
    }
  }
  return scalar;
}

}  // namespace linesurf
