#pragma once
// The point properties a hybrid's segments take from the points they replaced (beyond the
// thesis, which has colour only): shared by the (ε,δ) (§3.1), shape-approximation (§3.2) and
// curvature-line (§9.2) extractions. Rule: docs/decisions.md "Point attributes on kept points and
// segments".
#include <cstdint>
#include <span>
#include <string_view>

#include "linesurf/core/model.h"

namespace linesurf::detail {

/// Whether a point property holds a class (a label, not a quantity): `classification` (LAS),
/// `class` (the synthetic scenes) or `label`. A segment takes its members' mode of it.
bool isClassProperty(std::string_view name);

/// Sets out.segmentProperties from cloud.pointProperties (those with one value per point):
/// owner[j] = the segment of out that replaced point j of the cloud, or kKeptPoint (UINT32_MAX).
/// A segment gets its members' mean (computed in double), or for a class property the mode (ties:
/// the smallest value). A segment without members (none owns it) gets 0. Deterministic.
void setSegmentProperties(HybridModel& out, const HybridModel& cloud, std::span<const uint32_t> owner);

}  // namespace linesurf::detail
