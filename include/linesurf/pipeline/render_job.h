#pragma once
/// What `linesurf render` does around the renderer, as a library call shared by every front end
/// (the CLI and the Python module), so that both give the same image for the same options:
///   1. prepareForRendering: segment radii where missing, the §6.1 geometry stage for raw scans
///      without normals or radii (k nearest neighbours), then every radius times radiusScale;
///   2. viewCameras: the orbit view auto-framed on the bounding sphere, N spread views, or a
///      look-at camera, with near/far planes hugging the model.
/// Every option struct here holds its defaults and validates with OptionError (core/options.h).
#include <optional>
#include <string>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/mesh_render.h"
#include "linesurf/render/render_options.h"
#include "linesurf/render/render_stats.h"

namespace linesurf {

/// The camera of a render (thesis §6.2.2). Angles in degrees.
struct ViewOptions {
  int width = 512, height = 512;  ///< image size, [1, 16384] pixels per side ("size")
  float azimuth = 30;    ///< orbit azimuth about the up axis (0 = from the front axis)
  float elevation = 20;  ///< orbit elevation towards the up axis, [-90, 90]
  float distance = 0;    ///< orbit distance from the centre; 0 frames the bounding sphere; >= 0
  float zoom = 1;        ///< divides the framed distance, [1e-3, 1e3]
  float fov = Camera::kDefaultFovY;  ///< vertical field of view, [1, 170]
  int views = 0;         ///< > 0: this many views spread over the sphere, [0, 10000]
  Vec3f upAxis = Vec3f(0, 1, 0);  ///< world up of the orbit: a coordinate axis (+-x, +-y, +-z)
  /// Look-at camera when eye or target is set: eye defaults to 3 radii in front (+z) of the
  /// centre, target to the centre, up to +y.
  std::optional<Vec3f> eye, target, up;
};

/// Throws OptionError naming the first bad field (size as "size").
void validate(const ViewOptions& options);

/// "x", "-z", ... -> unit axis; throws OptionError("upAxis") for anything else.
Vec3f parseUpAxis(const std::string& text);

/// "white", "black", "transparent" (or "none"), "#rrggbb", or "R,G,B[,A]" in [0, 1]; throws
/// OptionError(field) otherwise.
Color parseColor(const std::string& field, const std::string& text);
/// parseColor("background", text).
Color parseBackground(const std::string& text);

/// The cameras of a view: one, or `views` spread ones, of a model drawn in `frame`
/// (io/model_frame.h): eye, target and distance are given in object units and mapped into it.
/// Validates first.
std::vector<Camera> viewCameras(const BoundingSphere& sphere, const ViewOptions& options, const ModelFrame& frame = {});

/// Preparation of a model before rendering.
struct PrepareOptions {
  int k = 12;              ///< neighbours for the normals/radii of raw scans (§6.1), [3, 256]
  float radiusScale = 1;   ///< multiplies every primitive radius, [1e-3, 1e3]
  ProgressFn progress;
};
void validate(const PrepareOptions& options);

/// Throws OptionError for a supersampling outside [1, 16] (as MeshRenderer does), so that a front
/// end refuses it before reading the mesh.
void validate(const MeshRenderOptions& options);

/// What the preparation did (for the CLI summary).
struct PrepareReport {
  size_t segmentRadiiEstimated = 0;  ///< segments without a radius that got one
  bool computedNormals = false, computedRadii = false;  ///< the §6.1 stage ran for the points
  double geometrySeconds = 0;
};

/// Normals and / or radii of points that lack them from the §6.1 geometry (k neighbours); in a
/// hybrid model points without a radius get their neighbour spacing. Nothing for models whose
/// points carry both. Fills the report's computed* fields.
void estimateMissingPointGeometry(HybridModel& model, int k, PrepareReport& report, const ProgressFn& progress = {});

/// The model as `linesurf render` draws it: segment radii estimated where missing,
/// estimateMissingPointGeometry, then every radius times radiusScale. Validates first. Call it
/// after moving the model into its normalising frame (io/model_frame.h).
PrepareReport prepareForRendering(HybridModel& model, const PrepareOptions& options = {});

/// A picture is called mostly back faces when more than this share of the pixels a two-sided
/// render covers show the back of the surface or nothing (RenderStats::backFacingShare). A closed,
/// outward-oriented scan shows 0-3% at its silhouette, vegetation a few more.
inline constexpr double kBackFacingWarnShare = 0.25;

/// One line saying that the picture of `what` shows mostly the back of its surface, and what to
/// do, when stats (summed over the views, RenderOptions::facingCheck on) say so; else "".
std::string backFacingWarning(const RenderStats& stats, const std::string& what);

/// Depth buffer as grey: near = white, far = dark, empty = transparent (the CLI's --depth-out).
Image depthAsGrey(const Image& depth);

}  // namespace linesurf
