// The output stage of `normals` out of core (see normals_writer.h).
#include "ooc/normals_writer.h"

#include <array>
#include <map>
#include <string>
#include <tuple>

#include "linesurf/core/error.h"

namespace linesurf::ooc::detail {

void writeNormals(const Run& r, const std::vector<uint8_t>& flip, const std::vector<size_t>& nodeOffset, float avgSpacing) {
  const uint64_t n = r.info.count;
  // The input's properties and the curvature's (addCurvatureProperties' names) in the order
  // writeModel writes pointProperties: sorted by name, the curvature replacing an input
  // property of the same name as it does in memory. source[e]: the curvature value (0..4) or
  // the input attribute (kFromInput + its index).
  const bool curv = r.curvatureOut();
  static const std::array<const char*, 5> kCurvature = {"dmin_x", "dmin_y", "dmin_z", "k_max", "k_min"};
  constexpr size_t kFromInput = 8;
  std::map<std::string, size_t> sourceOf;
  const size_t na = r.attrFloats(), colorFloats = r.info.colors ? 4 : 0;
  for (size_t j = 0; j < r.info.properties.size(); ++j) sourceOf[r.info.properties[j]] = kFromInput + colorFloats + j;
  if (curv)
    for (size_t c = 0; c < kCurvature.size(); ++c) sourceOf[kCurvature[c]] = c;
  std::vector<std::string> extraNames;
  std::vector<size_t> source;
  for (const auto& [name, from] : sourceOf) extraNames.push_back(name), source.push_back(from);
  const size_t ne = extraNames.size();
  PlyPointWriter w(r.out, n, r.info.comments, true, true, "", extraNames, r.info.colors);
  const size_t T = r.tileIds.size();
  std::vector<uint64_t> done(T, 0);  // records consumed per tile
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad, extra, colors;
  float cv5[5] = {0, 0, 0, 0, 0};
  std::vector<uint8_t> filled;
  const size_t rs = r.recordBytes();
  for (size_t blk = 0; blk < r.blocks; ++blk) {
    const uint64_t b0 = uint64_t(blk) * kBlock, b1 = std::min(n, b0 + kBlock);
    const size_t m = size_t(b1 - b0);
    pos.assign(m, Vec3f::Zero());
    nrm.assign(m, Vec3f::Zero());
    rad.assign(m, 0.0f);
    extra.assign(m * ne, 0.0f);
    colors.assign(m * colorFloats, 0.0f);
    filled.assign(m, 0);
    for (size_t d = 0; d < T; ++d) {
      const uint32_t cnt = r.blockCounts[d * r.blocks + blk];
      if (cnt == 0) continue;
      Points p;
      r.decode(readRange(r.cellPath(r.tileIds[d]), done[d] * rs, uint64_t(cnt) * rs), p);
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
          cv5[0] = dMin.x(), cv5[1] = dMin.y(), cv5[2] = dMin.z(), cv5[3] = kMax, cv5[4] = kMin;
        }
        const float* a = p.att.data() + i * na;
        for (size_t c = 0; c < colorFloats; ++c) colors[o * 4 + c] = a[c];
        for (size_t e = 0; e < ne; ++e) extra[o * ne + e] = source[e] >= kFromInput ? a[source[e] - kFromInput] : cv5[source[e]];
      }
      done[d] += cnt;
    }
    for (uint8_t f : filled)
      if (!f) throwIo(r.dir.string(), "a point is missing from the tiles (the folder was changed during the run?)");
    w.write(pos.data(), nrm.data(), rad.data(), m, ne ? extra.data() : nullptr, colorFloats ? colors.data() : nullptr);
    reportProgress(r.o.progress, "write", double(b1) / double(n));
  }
  w.finish();
}

}  // namespace linesurf::ooc::detail
