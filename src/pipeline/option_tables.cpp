#include "linesurf/pipeline/option_tables.h"

#include <fmt/format.h>

namespace linesurf {

std::string zThresholdDefaultText() {
  return fmt::format("{} (primitive) or {} (fixed)", defaultZThreshold(ZThresholdMode::PerPrimitive),
                     defaultZThreshold(ZThresholdMode::Fixed));
}

}  // namespace linesurf
