// libFuzzer target for the level-of-detail hierarchy reader (LodFile: the header, the node table
// and their one validation, then every block). Bad input must end in linesurf::Error with a
// one-line message; a file the reader accepts must keep the promises the frame's assembly relies
// on: the blocks within the file together no larger than the file (so nothing is sized beyond
// it), one parent per node, and blocks that read as their table says. Any allocation a count
// could blow up is caught by libFuzzer's -malloc_limit_mb / -rss_limit_mb.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_common.h"
#include "linesurf/lod/lod.h"

namespace {

// The reader works on a path (it reads nodes by byte range): one scratch file per process.
const std::string& scratch() {
  static const std::string p =
      (std::filesystem::temp_directory_path() / ("linesurf_lod_fuzz_" + std::to_string(getpid()) + ".lod")).string();
  return p;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  {
    std::ofstream out(scratch(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    const linesurf::lod::LodFile f(scratch());
    const auto& nodes = f.nodes();
    uint64_t held = 0;
    std::vector<int> parents(nodes.size(), 0);
    for (uint32_t i = 0; i < nodes.size(); ++i) {
      if (f.inFile(i)) held += nodes[i].size;
      if (!nodes[i].leaf)
        for (uint32_t c = nodes[i].firstChild; c < nodes[i].firstChild + nodes[i].childCount; ++c) ++parents[c];
    }
    if (held > size) std::abort();  // overlapping blocks were accepted
    for (size_t i = 1; i < parents.size(); ++i)
      if (parents[i] != 1) std::abort();  // a DAG or an orphan was accepted
    for (uint32_t i = 0; i < nodes.size(); ++i) {
      try {
        const linesurf::lod::NodeData d = f.readNode(i);
        if (d.points.size() != nodes[i].points || d.segments.size() != nodes[i].segments) std::abort();
      } catch (const linesurf::Error& e) {
        fuzz::checkMessage(e);
      }
    }
  } catch (const linesurf::Error& e) {
    fuzz::checkMessage(e);
  }
  return 0;
}
