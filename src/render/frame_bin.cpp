// Stage 2 of a frame (frame.h): binning. Every visible primitive goes to every tile its bounds
// touch; each tile's list is in primitive order (points, then segments), so the image does not
// depend on the threads (thesis §6.2).
#include <algorithm>

#include "cpu_time.h"
#include "frame.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"

namespace linesurf::detail {

void binFrame(const FramePlan& plan, FrameBuffers& buf, RenderStats& st) {
  Timer t;
  const size_t tiles = plan.tiles, chunks = plan.chunks;
  // offsets tile-major, chunk-minor: a chunk's bins follow the earlier chunks' in each tile
  buf.tileStart.resize(tiles + 1);
  buf.offset.resize(chunks * tiles);
  size_t run = 0;
  for (size_t tile = 0; tile < tiles; ++tile) {
    buf.tileStart[tile] = run;
    for (size_t c = 0; c < chunks; ++c) {
      buf.offset[c * tiles + tile] = run;
      run += buf.counts[c * tiles + tile];
    }
  }
  buf.tileStart[tiles] = run;
  if (buf.refs.size() < run) buf.refs.resize(run);
  uint32_t* const refs = buf.refs.data();
  const TileSpan* const spans = buf.pointTiles.data();
  const PrimitiveStatus* const segStatus = buf.segStatus.data();
  const TileSpan* const segTiles = buf.segTiles.data();
  const uint8_t* const segLod = plan.lod ? buf.segLod.data() : nullptr;
  auto fillSpan = [&](size_t* off, const TileSpan& s, uint32_t ref) {
    for (int ty = s.y0; ty <= s.y1; ++ty)
      for (int tx = s.x0; tx <= s.x1; ++tx) refs[off[size_t(ty) * size_t(plan.tilesX) + size_t(tx)]++] = ref;
  };
  parallelFor(0, chunks, [&](size_t c) {
    const double t0 = threadCpuSeconds();
    size_t* off = buf.offset.data() + c * tiles;
    if (c < plan.pointChunks) {
      for (size_t j = c * plan.chunkPoints, e = j + buf.chunkVisible[c]; j < e; ++j) fillSpan(off, spans[j], uint32_t(j));
    } else {
      const size_t c0 = (c - plan.pointChunks) * plan.segChunkSize;
      for (size_t i = c0, e = std::min(plan.ns, c0 + plan.segChunkSize); i < e; ++i)
        if (visible(segStatus[i]))
          fillSpan(off, segTiles[i], uint32_t((plan.lod && segLod[i] ? plan.lodBase : plan.pointSlots) + i));
    }
    buf.chunkSeconds[c] = threadCpuSeconds() - t0;
  }, 1);
  for (double s : buf.chunkSeconds) st.binThreadSeconds += s;
  st.tileBins = run;
  st.binSeconds = t.seconds();
}

}  // namespace linesurf::detail
