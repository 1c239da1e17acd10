// The thesis's published figures of §7 (Tables 1-5), and which shared model stands for which
// thesis model (per ../shared/data/README.md), for the side-by-side tables of results.md.
#include <array>
#include <string>

#include "linesurf/eval/experiment.h"

namespace linesurf {
namespace {

struct Row123 {
  const char* model;
  double input, points, segments, mse, nccm, speedupPercent;
};

// Table 1: (eps, delta) error bounded algorithm.
constexpr std::array<Row123, 10> kTable1 = {{
    {"Armadillo", 172974, 153169, 2793, 0.0016, 1.0, 7.27},
    {"Ball joint", 137062, 89060, 6202, 0.0036, 0.9999, 23.77},
    {"Golf club", 209779, 52287, 12887, 0.0042, 0.9993, 57.25},
    {"Igea artifact", 134345, 75565, 6823, 0.0035, 0.9999, 31.38},
    {"Male", 303380, 90457, 6993, 0.0101, 1.0, 30.19},
    {"Rabbit", 67038, 46047, 2789, 0.0042, 0.998, 21.35},
    {"Rocker arm", 40177, 27132, 1502, 0.0015, 1.0, 22.07},
    {"Santa", 75781, 62360, 1849, 0.0019, 0.9998, 12.57},
    {"Screwdriver", 27152, 17479, 1058, 0.0039, 0.9998, 21.80},
    {"Teeth casting", 116604, 65250, 4287, 0.003, 1.0006, 41.99},
}};

// Table 2: shape approximation, greedy clustering.
constexpr std::array<Row123, 10> kTable2 = {{
    {"Armadillo", 172974, 131284, 8391, 0.0043, 0.9995, 10.64},
    {"Ball joint", 137062, 68831, 11616, 0.0057, 0.9993, 28.65},
    {"Golf club", 209779, 27335, 13391, 0.0086, 0.9972, 65.96},
    {"Igea artifact", 134345, 52920, 12391, 0.0051, 0.9995, 38.13},
    {"Male", 303380, 72863, 12065, 0.0151, 0.9992, 33.93},
    {"Rabbit", 67038, 27844, 6406, 0.006, 0.9994, 35.10},
    {"Rocker arm", 40177, 14609, 2607, 0.0047, 0.9991, 43.29},
    {"Santa", 75781, 48922, 4650, 0.0043, 0.9991, 22.26},
    {"Screwdriver", 27152, 11126, 2050, 0.0072, 0.9994, 34.03},
    {"Teeth casting", 116604, 43852, 5734, 0.0069, 0.9994, 55.06},
}};

// Table 3: shape approximation, hierarchical distortion minimized clustering.
constexpr std::array<Row123, 10> kTable3 = {{
    {"Armadillo", 172974, 141864, 6720, 0.0043, 0.9995, 10.18},
    {"Ball joint", 137062, 79741, 11075, 0.0049, 0.9994, 24.01},
    {"Golf club", 209779, 37754, 19149, 0.0058, 0.9993, 55.75},
    {"Igea artifact", 134345, 62780, 12800, 0.0047, 0.9998, 31.69},
    {"Male", 303380, 86106, 10814, 0.0136, 0.9995, 27.54},
    {"Rabbit", 67038, 35037, 5974, 0.0054, 0.9997, 23.38},
    {"Rocker arm", 40177, 17342, 3347, 0.0045, 0.9996, 36.45},
    {"Santa", 75781, 53335, 4249, 0.0041, 0.9995, 18.33},
    {"Screwdriver", 27152, 12689, 2311, 0.0073, 0.9989, 35.81},
    {"Teeth casting", 116604, 54407, 8316, 0.0068, 0.9985, 43.19},
}};

// Table 4: number of clusters, greedy and hierarchical.
struct Row4 {
  const char* model;
  double greedy, hierarchical;
};
constexpr std::array<Row4, 10> kTable4 = {{
    {"Armadillo", 56173, 49211},  {"Ball joint", 20378, 17807}, {"Golf club", 5576, 5892},
    {"Igea artifact", 17062, 14627}, {"Male", 22297, 20107},    {"Rabbit", 7784, 7710},
    {"Rocker arm", 7574, 6941},   {"Santa", 19357, 17767},      {"Screwdriver", 4564, 4310},
    {"Teeth casting", 18467, 17003},
}};

// Table 5: contour-plane extraction, pure point vs. pure line-segment models, 20 views.
struct Row5 {
  const char* model;
  double points, segments, mean, std;
};
constexpr std::array<Row5, 9> kTable5 = {{
    {"Bunny", 128642, 26834, 0.13, 2.91},   {"Flamingo", 126938, 27876, 0.12, 2.70},
    {"Al", 163205, 46595, 0.09, 2.17},      {"Gargoyle", 146704, 46106, 0.09, 1.88},
    {"Dragon", 241893, 78305, 0.19, 3.62},  {"Buddha", 338709, 115883, 0.31, 4.45},
    {"Horse", 76601, 26518, 0.02, 1.56},    {"Skull", 156434, 57247, 0.04, 1.83},
    {"Skeleton", 221856, 87838, 0.17, 3.89},
}};

struct NameMap {
  const char* prefix;
  const char* thesis;
};
// File stem prefix -> thesis model (shared data README, "Thesis model" column).
constexpr std::array<NameMap, 18> kNames = {{
    {"igea", "Igea artifact"},   {"armadillo", "Armadillo"}, {"rockerarm", "Rocker arm"},
    {"rocker_arm", "Rocker arm"}, {"rocker-arm", "Rocker arm"}, {"santa", "Santa"},
    {"screwdriver", "Screwdriver"}, {"bunny", "Bunny"},      {"dragon", "Dragon"},
    {"horse", "Horse"},          {"gargoyle", "Gargoyle"},   {"al", "Al"},
    {"buddha", "Buddha"},        {"skull", "Skull"},         {"flamingo", "Flamingo"},
    {"skeleton", "Skeleton"},    {"golf", "Golf club"},      {"teeth", "Teeth casting"},
}};

std::string lower(std::string s) {
  for (char& c : s) c = char(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return s;
}

}  // namespace

std::string thesisModelFor(const std::string& fileStem) {
  const std::string s = lower(fileStem);
  for (const NameMap& m : kNames) {
    const std::string p = m.prefix;
    // The prefix must be the whole stem or be followed by a separator ("al_mesh", not "alpha").
    if (s.rfind(p, 0) == 0 && (s.size() == p.size() || s[p.size()] == '_' || s[p.size()] == '-' || s[p.size()] == '.'))
      return m.thesis;
  }
  return "";
}

std::optional<ThesisFigures> thesisFigures(const std::string& thesisModel, int table) {
  if (thesisModel.empty()) return std::nullopt;
  ThesisFigures f;
  f.model = thesisModel;
  f.table = table;
  if (table >= 1 && table <= 3) {
    const auto& rows = table == 1 ? kTable1 : table == 2 ? kTable2 : kTable3;
    for (const Row123& r : rows) {
      if (thesisModel != r.model) continue;
      f.inputPoints = r.input;
      f.points = r.points;
      f.segments = r.segments;
      f.mse = r.mse;
      f.nccm = r.nccm;
      f.speedup = r.speedupPercent / 100.0;
      if (table > 1)
        for (const Row4& c : kTable4)
          if (thesisModel == c.model) f.clusters = table == 2 ? c.greedy : c.hierarchical;
      return f;
    }
    return std::nullopt;
  }
  if (table == 5) {
    for (const Row5& r : kTable5) {
      if (thesisModel != r.model) continue;
      f.inputPoints = r.points;
      f.points = r.points;
      f.segments = r.segments;
      f.meanAbsDiff = r.mean;
      f.stdAbsDiff = r.std;
      return f;
    }
  }
  return std::nullopt;
}

}  // namespace linesurf
