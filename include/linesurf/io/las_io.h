#pragma once
/// LAS, the ASPRS LiDAR exchange format: versions 1.0-1.4, point data formats 0-10, read and
/// written without a library (docs/file-format.md "LAS", docs/decisions.md "LAS without a
/// library"). readModel/writeModel (model_io.h) dispatch .las here; .laz is refused.
///
/// What a LAS file carries beyond the point record travels in model.comments, so that every
/// command (in memory and out of core) and every PLY file keep it without knowing LAS:
///   linesurf_origin X Y Z        double-precision object-space origin the float positions are
///                                relative to (absent: zero)
///   linesurf_las_scale SX SY SZ  the file's quantisation, reused when the model is written back
///   linesurf_las_offset OX OY OZ   as LAS, so that the integer X Y Z records come back bit-exact
///   linesurf_up_axis z           LAS is z-up
///   linesurf_las_crs RECORD HEX  a coordinate reference system record (GeoTIFF keys, WKT),
///                                written back as it was
#include <filesystem>
#include <string>
#include <string_view>

#include "linesurf/core/model.h"

namespace linesurf {

inline constexpr std::string_view kOriginComment = "linesurf_origin";
inline constexpr std::string_view kLasScaleComment = "linesurf_las_scale";
inline constexpr std::string_view kLasOffsetComment = "linesurf_las_offset";
inline constexpr std::string_view kUpAxisComment = "linesurf_up_axis";
inline constexpr std::string_view kLasCrsComment = "linesurf_las_crs";

/// The origin model positions are relative to (the `linesurf_origin` comment), zero when there
/// is none: object-space point = origin + position. Throws BadParameter for a malformed comment.
Vec3d modelOrigin(const HybridModel& model);

/// The up axis a file recorded (the `linesurf_up_axis` comment: "z" for LAS), empty when none.
inline std::string recordedUpAxis(const HybridModel& model) {
  for (const std::string& c : model.comments)
    if (c.size() > kUpAxisComment.size() + 1 && c.compare(0, kUpAxisComment.size(), kUpAxisComment) == 0 &&
        c[kUpAxisComment.size()] == ' ')
      return c.substr(kUpAxisComment.size() + 1);
  return {};
}

struct LasWriteOptions {
  /// Point data format 0-10; -1: 7 (with RGB) when the model has colours, else 6. Formats 0-5
  /// hold a class of 0-31 only.
  int pointFormat = -1;
};

/// LAS from bytes (fuzzing, tests): `nameForMessages` stands for the path in error messages.
/// Checked as readModel checks (validateModel).
HybridModel readLasModelFromMemory(std::string_view bytes, const std::string& nameForMessages);

/// The LAS 1.4 file of a point model. Throws BadParameter for a model with segments, an
/// attribute the format cannot hold, or a point property name longer than LAS's 32 bytes.
std::string lasBytes(const HybridModel& model, const LasWriteOptions& options, const std::string& nameForMessages);

/// lasBytes written through writeFileAtomically.
void writeLasModel(const std::filesystem::path& path, const HybridModel& model, const LasWriteOptions& options = {});

}  // namespace linesurf
