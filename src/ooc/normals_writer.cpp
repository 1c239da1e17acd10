// The output stage of `normals` out of core (see normals_writer.h).
#include "ooc/normals_writer.h"

#include <tuple>

#include "linesurf/core/error.h"

namespace linesurf::ooc::detail {

void writeNormals(const Run& r, const std::vector<uint8_t>& flip, const std::vector<size_t>& nodeOffset, float avgSpacing) {
  const uint64_t n = r.info.count;
  // Curvature properties in the order writeModel writes them (addCurvatureProperties' names, sorted).
  const bool curv = r.curvatureOut();
  const std::vector<std::string> extraNames =
      curv ? std::vector<std::string>{"dmin_x", "dmin_y", "dmin_z", "k_max", "k_min"} : std::vector<std::string>{};
  PlyPointWriter w(r.out, n, r.info.comments, true, true, "", extraNames);
  const size_t T = r.tileIds.size();
  std::vector<uint64_t> done(T, 0);  // records consumed per tile
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad, extra;
  std::vector<uint8_t> filled;
  const size_t rs = r.recordBytes();
  for (size_t blk = 0; blk < r.blocks; ++blk) {
    const uint64_t b0 = uint64_t(blk) * kBlock, b1 = std::min(n, b0 + kBlock);
    const size_t m = size_t(b1 - b0);
    pos.assign(m, Vec3f::Zero());
    nrm.assign(m, Vec3f::Zero());
    rad.assign(m, 0.0f);
    extra.assign(m * extraNames.size(), 0.0f);
    filled.assign(m, 0);
    for (size_t d = 0; d < T; ++d) {
      const uint32_t cnt = r.blockCounts[d * r.blocks + blk];
      if (cnt == 0) continue;
      Points p;
      decodeRecords(readRange(r.cellPath(r.tileIds[d]), done[d] * rs, uint64_t(cnt) * rs), r.normalsIn, r.radiusIn, p);
      const std::string cv = curv ? readRange(r.curvaturePath(r.tileIds[d]), done[d] * kCurvatureRecord,
                                              uint64_t(cnt) * kCurvatureRecord)
                                  : std::string();
      const std::string res = readRange(r.resultPath(r.tileIds[d]), 8 + sizeof(TileSummary) + done[d] * kResultRecord,
                                        uint64_t(cnt) * kResultRecord);
      for (size_t i = 0; i < cnt; ++i) {
        const uint64_t gi = p.idx[i];
        if (gi < b0 || gi >= b1 || filled[gi - b0]) throwIo(r.cellPath(r.tileIds[d]).string(), "tile files do not match the manifest");
        const InteriorResult x = decodeInterior(res.data() + i * kResultRecord);
        const size_t o = size_t(gi - b0);
        filled[o] = 1;
        pos[o] = p.pos[i];
        nrm[o] = flip[nodeOffset[d] + x.component] ? Vec3f(-x.normal) : x.normal;
        // Radius rule of applyGeometry: cover radius, else spacing, else the average spacing.
        rad[o] = x.cover > 0 ? x.cover : x.spacing > 0 ? x.spacing : avgSpacing;
        if (curv) {
          const char* q = cv.data() + i * kCurvatureRecord;
          float kMin = getRaw<float>(q), kMax = getRaw<float>(q);
          Vec3f dMin = getRaw<Vec3f>(q);
          const Vec3f dMax = getRaw<Vec3f>(q);
          // A flipped tile component: with -n every directional curvature changes sign, so the
          // principal values swap and negate and the minimum direction is the maximum one.
          if (flip[nodeOffset[d] + x.component]) std::tie(kMin, kMax, dMin) = std::make_tuple(-kMax, -kMin, dMax);
          float* e = extra.data() + o * 5;
          e[0] = dMin.x(), e[1] = dMin.y(), e[2] = dMin.z(), e[3] = kMax, e[4] = kMin;
        }
      }
      done[d] += cnt;
    }
    for (uint8_t f : filled)
      if (!f) throwIo(r.dir.string(), "a point is missing from the tiles (the folder was changed during the run?)");
    w.write(pos.data(), nrm.data(), rad.data(), m, curv ? extra.data() : nullptr);
    reportProgress(r.o.progress, "write", double(b1) / double(n));
  }
  w.finish();
}

}  // namespace linesurf::ooc::detail
