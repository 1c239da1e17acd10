// The point properties a hybrid's segments take from their points (beyond the thesis; see
// detail/segment_attributes.h).
#include "detail/segment_attributes.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace linesurf::detail {

bool isClassProperty(std::string_view name) { return name == "classification" || name == "class" || name == "label"; }

void setSegmentProperties(HybridModel& out, const HybridModel& cloud, std::span<const uint32_t> owner) {
  const size_t ns = out.segments.size(), n = cloud.points.size();
  for (const auto& [name, values] : cloud.pointProperties) {
    if (values.size() != n || owner.size() != n) continue;
    std::vector<float>& dst = out.segmentProperties[name];
    dst.assign(ns, 0.0f);
    if (!isClassProperty(name)) {
      std::vector<double> sum(ns, 0.0);
      std::vector<uint32_t> count(ns, 0);
      for (size_t j = 0; j < n; ++j)
        if (owner[j] < ns) sum[owner[j]] += double(values[j]), ++count[owner[j]];
      for (size_t s = 0; s < ns; ++s)
        if (count[s]) dst[s] = float(sum[s] / double(count[s]));
      continue;
    }
    // Mode: (segment, value) pairs sorted, the longest run per segment, the first (smallest) on ties.
    std::vector<std::pair<uint32_t, float>> pairs;
    for (size_t j = 0; j < n; ++j)
      if (owner[j] < ns) pairs.emplace_back(owner[j], values[j]);
    std::sort(pairs.begin(), pairs.end());
    std::vector<size_t> best(ns, 0);
    for (size_t a = 0; a < pairs.size();) {
      size_t b = a;
      while (b < pairs.size() && pairs[b] == pairs[a]) ++b;
      const uint32_t s = pairs[a].first;
      if (b - a > best[s]) best[s] = b - a, dst[s] = pairs[a].second;
      a = b;
    }
  }
}

}  // namespace linesurf::detail
