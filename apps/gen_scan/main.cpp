// linesurf_gen_scan [--scene terrain|room|facade [--truth TRUTH.ply]] [--color] OUT.ply N [SEED] [NOISE]:
// writes a synthetic scan of N points as binary PLY, streamed in chunks (bounded memory for any
// N), deterministic for a seed. Without --scene the closed surface of ooc/synthetic_scan.h
// (--color: with its deterministic 8-bit colour field);
// with it an open scene of ooc/synthetic_scene.h (terrain from the air, a room from inside, a
// street facade), and --truth writes the same points again with their true normals and class.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "linesurf/core/error.h"
#include "linesurf/ooc/synthetic_scan.h"
#include "linesurf/ooc/synthetic_scene.h"

namespace {

void usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s [--scene terrain|room|facade [--truth TRUTH.ply]] [--color] OUT.ply N [SEED=1] "
               "[NOISE=0.1 (fraction of the spacing)]\n",
               argv0);
}

}  // namespace

int main(int argc, char** argv) {
  // --scene, --truth and --color anywhere; everything else is positional, as it always was.
  std::string scene, truth;
  bool color = false;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--color") {
      color = true;
    } else if (a == "--scene" || a == "--truth") {
      if (i + 1 == argc) {
        usage(argv[0]);
        return 1;
      }
      (a == "--scene" ? scene : truth) = argv[++i];
    } else {
      pos.push_back(a);
    }
  }
  if (pos.size() < 2 || pos.size() > 4) {
    usage(argv[0]);
    return 1;
  }
  linesurf::ooc::SyntheticSceneOptions so;
  if (!scene.empty()) {
    if (scene == "terrain") so.kind = linesurf::ooc::SceneKind::Terrain;
    else if (scene == "room") so.kind = linesurf::ooc::SceneKind::Room;
    else if (scene == "facade") so.kind = linesurf::ooc::SceneKind::Facade;
    else {
      std::fprintf(stderr, "%s: --scene must be terrain, room or facade, not '%s'\n", argv[0], scene.c_str());
      return 1;
    }
  } else if (!truth.empty()) {
    std::fprintf(stderr, "%s: --truth needs --scene (the closed scan has no truth file)\n", argv[0]);
    return 1;
  }
  if (color && !scene.empty()) {
    std::fprintf(stderr, "%s: --color is for the closed scan (the scenes carry a class, not a colour)\n", argv[0]);
    return 1;
  }
  linesurf::ooc::SyntheticScanOptions o;
  o.color = color;
  try {
    const long long n = std::stoll(pos[1]);
    if (n < 1) throw std::invalid_argument("N");
    o.count = uint64_t(n);
    if (pos.size() > 2) o.seed = std::stoull(pos[2]);
    if (pos.size() > 3) o.noise = std::stod(pos[3]);
    if (!(o.noise >= 0)) throw std::invalid_argument("NOISE");
  } catch (const std::exception&) {
    std::fprintf(stderr, "%s: N must be a positive integer, SEED a non-negative integer, NOISE >= 0\n", argv[0]);
    return 1;
  }
  try {
    if (scene.empty()) {
      linesurf::ooc::writeSyntheticScan(pos[0], o);
    } else {
      so.count = o.count, so.seed = o.seed, so.noise = o.noise;
      linesurf::ooc::writeSyntheticScene(pos[0], so, truth);
    }
  } catch (const linesurf::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 3;
  }
  return 0;
}
