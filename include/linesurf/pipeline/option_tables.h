#pragma once
/// The option tables (core/option_table.h): every user-facing field of the option structs of the
/// render pipeline and of the extractions, described once. describeOptions(s, v) calls
///   v.group(name, title)      before a group of related fields (the CLI's help sections), and
///   v(field, OptionSpec)      for each field (a reference into `s`, or a SizeRef / AxisRef /
///                             BackgroundRef / RgbRef for a field written in a form of its own).
/// Defaults are the structs' own; ranges are what the structs' validate() accept.
/// Fields a front end fills from something else (RenderOptions' output buffers, progress
/// callbacks, record-keeping switches) are not options and are left out.
#include <span>
#include <string>

#include "linesurf/core/option_table.h"
#include "linesurf/surface/surface_error.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/curvature_lines.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/feature_lines.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/drawing.h"
#include "linesurf/render/mesh_render.h"
#include "linesurf/render/render_options.h"
#include "linesurf/surface/mesh_extract.h"

namespace linesurf {

inline std::span<const EnumName<ZThresholdMode>> enumNames(ZThresholdMode) {
  static constexpr EnumName<ZThresholdMode> k[] = {{"primitive", ZThresholdMode::PerPrimitive},
                                                   {"fixed", ZThresholdMode::Fixed}};
  return k;
}
inline std::span<const EnumName<SegmentMethod>> enumNames(SegmentMethod) {
  static constexpr EnumName<SegmentMethod> k[] = {
      {"screen", SegmentMethod::ScreenSpace}, {"approx", SegmentMethod::Approx}, {"reference", SegmentMethod::Reference}};
  return k;
}
inline std::span<const EnumName<DrawStyle>> enumNames(DrawStyle) {
  static constexpr EnumName<DrawStyle> k[] = {
      {"splat", DrawStyle::Splat}, {"lines", DrawStyle::Lines}, {"hatch", DrawStyle::Hatch}};
  return k;
}
inline std::span<const EnumName<ClusteringMethod>> enumNames(ClusteringMethod) {
  static constexpr EnumName<ClusteringMethod> k[] = {{"greedy", ClusteringMethod::Greedy},
                                                     {"hierarchical", ClusteringMethod::Hierarchical}};
  return k;
}
inline std::span<const EnumName<CurvatureFamily>> enumNames(CurvatureFamily) {
  static constexpr EnumName<CurvatureFamily> k[] = {
      {"min", CurvatureFamily::Min}, {"max", CurvatureFamily::Max}, {"both", CurvatureFamily::Both}};
  return k;
}
inline std::span<const EnumName<CurvatureFit>> enumNames(CurvatureFit) {
  static constexpr EnumName<CurvatureFit> k[] = {{"taubin", CurvatureFit::Taubin}, {"quadric", CurvatureFit::Quadric}};
  return k;
}
inline std::span<const EnumName<OrientSide>> enumNames(OrientSide) {
  static constexpr EnumName<OrientSide> k[] = {{"auto", OrientSide::Auto},
                                               {"outward", OrientSide::Outward},
                                               {"up", OrientSide::Up},
                                               {"towards", OrientSide::Towards},
                                               {"away-from", OrientSide::AwayFrom}};
  return k;
}

/// Text of the mode-dependent z threshold default (defaultZThreshold).
std::string zThresholdDefaultText();

/// The camera (thesis §6.2.2).
template <typename V>
void describeOptions(ViewOptions& o, V&& v) {
  v.group("camera", "Orbit view auto-framed on the bounding sphere, N views, or look-at");
  v(SizeRef{o.width, o.height}, {"size", "Image size WIDTHxHEIGHT, pixels per side", closedRange(1, 16384)});
  v(o.azimuth, {"azimuth", "Orbit azimuth about the up axis, degrees (0 = from the front axis)", anyFinite(), kUseAll});
  v(o.elevation, {"elevation", "Orbit elevation towards the up axis, degrees", closedRange(-90, 90), kUseAll});
  v(o.distance, {"distance", "Orbit distance from the centre, object units (0 = frame the model)", closedRange(0, 1e30)});
  v(o.zoom, {"zoom", "Divide the framed distance by this factor", closedRange(1e-3, 1e3)});
  v(o.fov, {"fov", "Vertical field of view, degrees", closedRange(1, 170), kUseAll});
  v(o.views, {"views", "Render N views spread over the sphere (deterministic; 0 = the one orbit view)",
              closedRange(0, 10000), kUseCli});
  v(AxisRef{o.upAxis}, {"upAxis", "World up axis of the orbit: x, y, z, -x, -y, -z (santa, rockerarm: z)", {}, kUseAll});
  v(o.eye, {"eye", "Look-at camera position x y z, object units"});
  v(o.target, {"target", "Look-at target x y z (default: the model's centre)"});
  v(o.up, {"up", "Look-at up vector x y z (default 0 1 0)"});
}

/// The model's preparation (§6.1 for raw scans).
template <typename V>
void describeOptions(PrepareOptions& o, V&& v) {
  v.group("preparation", "Normals and radii of raw scans (§6.1)");
  v(o.k, {"k", "Neighbours for the normals and radii of raw scans (§6.1)", closedRange(3, 256), kUseAll});
  v(o.radiusScale, {"radiusScale", "Multiply every primitive radius", closedRange(1e-3, 1e3)});
}

/// The splatting pipeline (thesis §4, §5, §6.2); render_options.h says why each default.
template <typename V>
void describeOptions(RenderOptions& o, V&& v) {
  v.group("filtering", "EWA resampling filter (§4.2.2)");
  v(o.prefilterVariance,
    {"prefilterVariance", "Screen prefilter variance, pixels^2 (0 = none)", closedRange(0, 100), kUseAll, "--prefilter"});
  v(o.cutoffRadius,
    {"cutoffRadius", "Resampling filter cut-off radius, standard deviations", closedRange(1, 5), kUseAll, "--cutoff"});
  v(o.reconstructionScale, {"reconstructionScale", "Reconstruction sigma as a fraction of the primitive radius",
                            closedRange(0.01, 4), kUseAll, "--recon-scale"});
  v(o.coverageGain, {"coverageGain",
                     "Coverage alpha (beyond the thesis): alpha = gain x the kernel sum over the model's kernel density "
                     "(0 = the thesis's normalised alpha; 1.25 for contour models at silhouettes, 1.5 with "
                     "--coverage-reach 0)",
                     closedRange(0, 100)});
  v(o.coverageReach, {"coverageReach",
                      "Coverage alpha only at silhouettes: pixels within this many pixels of the background or of a "
                      "farther layer (0 = everywhere)",
                      closedRange(0, 16)});
  v.group("visibility", "Modified Z^3 buffer (§6.2.3)");
  v(o.layers, {"layers", "Fragment layers per pixel", closedRange(1, RenderOptions::kMaxLayers)});
  v(o.tailLayers, {"tailLayers",
                   "Tail layers (beyond the thesis): a fragment outside 1.5x its primitive's own disc or strip (a "
                   "prefilter tail) occludes nothing and is composited only over the background"});
  v(o.tailCoverage, {"tailCoverage",
                     "Tail coverage (beyond the thesis): a pixel past a silhouette reached only by tails takes alpha "
                     "gain x its kernel sum over the model's median kernel density (0 = the normalised alpha 1)",
                     closedRange(0, 100)});
  v(o.zThresholdMode,
    {"zThresholdMode", "z threshold: primitive (delta-z, own depth extent) or fixed (thesis)", {}, kUseCliPython, "--z-mode"});
  static const std::string zDefault = zThresholdDefaultText();
  v(o.zThreshold, {"zThreshold",
                   "primitive: multiple of the primitive's depth extent; fixed: fraction of the bounding radius",
                   closedRange(0, 1e6), kUseAll, "", zDefault.c_str()});
  v(o.alphaOverride, {"alphaOverride", "Alpha of every primitive (order-independent transparency; -1 = the model's)",
                      OptionRange{0, 1, false, false, true, -1}, kUseCliPython, "--alpha"});
  v(o.backfaceCulling, {"backfaceCulling", "Drop back faces (off: two-sided lighting)", {}, kUseCliPython, "--no-cull"});
  v.group("shading", "Phong lighting (§6.2.2); defaults suit unit-free scans");
  v(o.material.ambient, {"ambient", "Ambient coefficient", closedRange(0, 1), kUseAll});
  v(o.material.diffuse, {"diffuse", "Diffuse coefficient", closedRange(0, 1), kUseAll});
  v(o.material.specular, {"specular", "Specular coefficient", closedRange(0, 1), kUseAll});
  v(o.material.shininess, {"shininess", "Phong exponent", closedRange(1e-3, 1e4), kUseAll});
  v(o.light.direction, {"light", "Direction towards the light x y z (camera space; world space without --headlight)",
                        {}, kUseAll});
  v(o.light.color, {"lightColor", "Colour of the light R G B (>= 0)"});
  v(o.light.headlight,
    {"headlight", "The light moves with the camera (off: --light is in world space)", {}, kUseCliPython, "--world-light"});
  v(RgbRef{o.defaultColor}, {"defaultColor", "Albedo R G B in [0, 1] of models without colours", {}, kUseAll, "--color"});
  v(o.perPixelLighting, {"perPixelLighting", "Light every fragment instead of Gouraud at the quad vertices"});
  v(BackgroundRef{o.background}, {"background", "white, black, transparent or R,G,B[,A] in [0, 1]", {}, kUseAll});
  v.group("segments", "Line-segment splats (§5)");
  v(o.segmentMethod, {"segmentMethod", "Line-segment filter: screen (erf), approx (§5.2.3 quads), reference"});
  v(o.segmentLod, {"segmentLod",
                   "Draw screen segments at most this many kernel sigmas long as one moment-matched point splat "
                   "(0 = every segment exact)",
                   closedRange(0, 4)});
  v.group("execution", "Execution (does not change the image)");
  v(o.tileSize, {"tileSize", "Screen tile side in pixels", closedRange(8, 1024)});
}

/// Drawings from the segments (thesis §9.4, §9.5); render/drawing.h says why each default.
template <typename V>
void describeOptions(DrawingOptions& o, V&& v) {
  v.group("drawing", "Drawings from the segments (§9.4, §9.5): strokes, hatching, silhouettes");
  v(o.style, {"style",
              "splat (shaded EWA splatting), lines (every visible segment as an ink stroke) or hatch (stroke density "
              "follows the shaded tone); lines and hatch also write .svg"});
  v(o.strokeWidth, {"strokeWidth", "Width of every stroke, pixels", closedRange(0.1, 64)});
  v(BackgroundRef{o.paper}, {"paper", "Paper colour: white, black, transparent, #rrggbb or R,G,B[,A] in [0, 1]"});
  v(BackgroundRef{o.ink}, {"ink", "Ink colour: black, white, #rrggbb or R,G,B[,A] in [0, 1]"});
  v(o.toneLevels, {"toneLevels", "Hatch: tones the shaded luminance is quantised to (0 = continuous)", closedRange(0, 256)});
  v(o.strokeDepthTolerance, {"strokeDepthTolerance",
                             "A stroke is visible within this many segment radii of the splat depth", aboveRange(0, 100)});
  v(o.silhouettes, {"silhouettes", "Draw silhouettes from the depth and normal buffers"});
  v(o.inBetween, {"inBetween", "Hatch: copies of the strokes halfway across where even all of them are too light"});
  v(o.crossHatch, {"crossHatch", "Hatch: a second family across the strokes where they cannot reach the tone"});
  v(o.strokeSeed, {"strokeSeed", "Seed of the strokes' order within a level of their nested priorities", atLeast(0)});
}

/// Triangle meshes drawn as the ground truth.
template <typename V>
void describeOptions(MeshRenderOptions& o, V&& v) {
  v.group("mesh", "Mesh files drawn as anti-aliased triangles");
  v(o.supersampling, {"supersampling", "Mesh: samples per pixel side (S x S per pixel)", closedRange(1, 16), kUseCli});
  v(o.smoothShading, {"smoothShading", "Mesh: normals interpolated from the vertex normals (off: face normals)", {}, kUseCli});
}

/// The §6.1 geometry stage. The commands bind the fields they use (see their sources).
template <typename V>
void describeOptions(GeometryOptions& o, V&& v) {
  v.group("geometry", "Point geometry (§6.1)");
  v(o.k, {"k", "Nearest neighbours per point for normals and spacing (§6.1)", closedRange(3, 256), kUseCliPython,
          "-k,--neighbours"});
  v(o.recomputeNormals, {"recomputeNormals", "Ignore normals in the input and compute them", {}, kUseCliPython, "--recompute"});
  v(o.orientNormals, {"orientNormals", "Orient computed normals by a minimum spanning tree", {}, kUseCliPython, "--no-orient"});
  v(o.orientationPenalty, {"orientationPenalty", "MST orientation: penalty on edges along the normals (0 = Hoppe's weight)",
                           closedRange(0, 1e6)});
  v(o.orient, {"orient",
               "Side the oriented normals face: auto (outward for objects, up for terrain), outward, up (+z), towards or "
               "away-from --viewpoint"});
  v(o.viewpoint, {"viewpoint", "Sensor position x y z for --orient towards / away-from, object units"});
  v(o.curvature, {"curvature", "Curvature (§6.1.2; needs the local Delaunay neighbours)"});
  v(o.curvatureFit, {"curvatureFit", "taubin (thesis §6.1.2) or quadric (height-function fit)"});
}

/// (epsilon, delta) extraction, thesis §3.1.
template <typename V>
void describeOptions(EpsDeltaOptions& o, V&& v) {
  v.group("eps-delta", "(epsilon, delta) extraction (§3.1)");
  v(o.epsilon, {"epsilon", "Distance tolerance, object space (0 = --epsilon-relative x the average spacing)",
                closedRange(0, 1e30)});
  v(o.epsilonRelative, {"epsilonRelative", "Distance tolerance as a fraction of the average neighbour spacing (§7.2)",
                        OptionRange{0, 1e6, true, false}, kUseCliPython, "--epsilon-rel"});
  v(o.epsilonNoise, {"epsilonNoise",
                     "Noisy scans: epsilon = the larger of --epsilon-rel x spacing and this many times the scan's "
                     "estimated noise (0 = off, the thesis)",
                     closedRange(0, 100)});
  v(o.delta, {"delta", "Normal tolerance on 1 - n_i.n_j (0.004 ~ 5.13 deg, §7.2)", closedRange(0, 2)});
  v(o.minReplaced, {"minReplaced", "Smallest number of points a segment may replace", closedRange(2, 2147483647)});
  v(o.maxReplaced, {"maxReplaced",
                    "Stop growing a segment at this many points (0 = no limit; else >= --min-replaced; bounds time on "
                    "long regular rows)",
                    closedRange(0, 2147483647)});
  v(o.provenance, {"provenance", "Record the input points each segment replaced (for verify-extraction)"});
  v(o.endpointNormals, {"endpointNormals", "Smooth line models: each segment carries the normals at its two ends"});
}

/// Shape-approximation extraction, thesis §3.2.
template <typename V>
void describeOptions(ShapeApproxOptions& o, V&& v) {
  v.group("shape-approx", "Shape approximation (§3.2)");
  v(o.method, {"method", "Clustering algorithm: greedy (§3.2.3.1) or hierarchical (§3.2.3.2)", {}, kUseCliPython,
               "--clustering"});
  v(o.clustering.deltaN, {"deltaN", "Normal variation tolerance on ||n(C) - n_j||^2 (0.008 ~ 5.1 deg, §7.2)",
                          OptionRange{0, 2, true, true}});
  v(o.clustering.seed, {"seed", "Seed of the hierarchical clustering's random seed points", atLeast(0)});
  v(o.clustering.maxIterations, {"maxIterations", "Hierarchical: reseeding iterations per split", closedRange(1, kMaxClusteringIterations)});
  v(o.radiusScale, {"radiusScale",
                    "Clouds without point radii only: segment half-width as a multiple of the cluster's spacing across "
                    "segments (with radii the width covers the replaced points' Voronoi cells)",
                    OptionRange{0, 1e3, true, false}});
  v(o.minClusterSize, {"minClusterSize", "Clusters with fewer points stay points (§3.2.4.1)", closedRange(2, 2147483647)});
  v(o.minRunPoints, {"minRunPoints", "Runs of influenced squares with fewer points stay points (§3.2.4.5)",
                     closedRange(2, 2147483647)});
  v(o.curvatureSwitchDegrees, {"curvatureSwitchDegrees",
                               "Use the minimum-curvature direction when it differs from the rectangle's by more than "
                               "this, degrees (90 = never)",
                               closedRange(0, 90)});
  v(o.curvatureCoherence, {"curvatureCoherence", "Use curvature directions only when their axial mean is at least this coherent (1 = never)",
                           closedRange(0, 1)});
  v(o.provenance, {"provenance", "Record the input points each segment replaced"});
  v(o.endpointNormals, {"endpointNormals", "Smooth line models: each segment carries the normals at its two ends"});
}

/// Lines of curvature traced on the MLS surface, thesis §9.2.
template <typename V>
void describeOptions(CurvatureLineOptions& o, V&& v) {
  v.group("curvature-lines", "Lines of curvature (§9.2)");
  v(o.epsilon, {"epsilon", "Distance tolerance, object space (0 = --epsilon-relative x the average spacing)",
                closedRange(0, 1e30)});
  v(o.epsilonRelative, {"epsilonRelative", "Distance tolerance as a fraction of the average neighbour spacing (§7.2)",
                        OptionRange{0, 1e6, true, false}, kUseCliPython, "--epsilon-rel"});
  v(o.delta, {"delta", "Normal tolerance on 1 - n_i.n_j along a segment (0.004 ~ 5.13 deg, §7.2)", closedRange(0, 2)});
  v(o.family, {"family", "Which lines: min (least curvature, the straightest), max, or both (a crossing net)"});
  v(o.separation, {"separation", "Largest line separation d_sep, average spacings (flat regions)", closedRange(1, 100)});
  v(o.minSeparation, {"minSeparation", "Smallest line separation, average spacings (at most --separation)",
                      closedRange(0.25, 100)});
  v(o.widthScale, {"widthScale", "Strip half-width as a multiple of d_sep / 2 (overlap of adjacent strips)",
                   closedRange(1, 3)});
  v(o.step, {"step", "Integration step, average spacings", OptionRange{0, 4, true, false}});
  v(o.minLength, {"minLength", "Drop lines shorter than this many d_sep (their points stay points)", closedRange(0, 100)});
  v(o.smoothingIterations, {"smoothingIterations", "Jacobi iterations smoothing the cross field", closedRange(0, 1000)});
  v(o.fieldDataWeight, {"fieldDataWeight", "Weight of the principal direction against the neighbours, per unit anisotropy",
                        closedRange(0, 1e6)});
  v(o.supportScale, {"supportScale", "MLS kernel support, spacings", closedRange(1.5, 10)});
  v(o.provenance, {"provenance", "Record the input points each segment replaced (for verify-extraction)"});
}

/// Feature lines (creases) of a cloud, thesis §9.5.
template <typename V>
void describeOptions(FeatureLineOptions& o, V&& v) {
  v.group("features", "Feature lines (§9.5)");
  v(o.angle, {"angle", "Smallest angle between the normals on the two sides of a crease, degrees", closedRange(5, 170)});
  v(o.linkRadius, {"linkRadius", "Neighbours and links within this many median spacings", closedRange(1, 8)});
  v(o.minLength, {"minLength", "Drop polylines shorter than this many spacings", closedRange(0, 1e6)});
  v(o.tolerance, {"tolerance", "Simplification tolerance (Douglas-Peucker), spacings", closedRange(0, 10)});
  v(o.robustNormals, {"robustNormals", "Normals from the robust MLS surface, sharp at creases (else the cloud's own)"});
  v(o.supportScale, {"supportScale", "MLS kernel support, spacings", closedRange(1.5, 10)});
}

/// Contour-plane extraction from a mesh, thesis §3.3.
template <typename V>
void describeOptions(ContourOptions& o, V&& v) {
  v.group("contour", "Contour planes (§3.3)");
  v(o.spacing, {"spacing",
                "Largest distance d between neighbouring segments, object units (0: --spacing-scale x min(mean edge, "
                "diagonal / --diagonal-divisions))",
                closedRange(0, 1e30)});
  v(o.spacingScale, {"spacingScale", "d as a multiple of min(mean edge length, diagonal / --diagonal-divisions), when --spacing is 0",
                     OptionRange{0, 1e6, true, false}});
  v(o.diagonalDivisions, {"diagonalDivisions",
                          "Default d at most the bounding-box diagonal / N, so coarse meshes are cut finely enough (0 = "
                          "mean edge only)",
                          closedRange(0, 1e6)});
  v(o.seed, {"seed", "Seed of the random plane orientation and offsets", atLeast(0)});
  v(o.familySwitchSine, {"familySwitchSine",
                         "Use P= unless its sin(theta) is below this and P|| cuts steeper (1: steeper family always; 0: P= only)",
                         closedRange(0, 1)});
  v(o.radiusScale, {"radiusScale", "Segment/point radius as a multiple of d (> 0.5 for a hole-free model)",
                    OptionRange{0, 100, true, false}});
  v(o.vertexNormals, {"vertexNormals", "Interpolate the mesh's vertex normals instead of the face normal"});
  v(o.endpointNormals, {"endpointNormals",
                        "Smooth line models: every segment carries the vertex normals at its endpoints (off: the "
                        "thesis's one normal per segment)",
                        {}, kUseCliPython, "--flat"});
  v(o.shadingNormals, {"shadingNormals", "Smooth models: points carry the interpolated vertex normal as shading normal"});
  v(o.pointMasses, {"pointMasses", "Points weigh the contour length they stand for (off: each weighs 1)"});
  v(o.mergeNormalDeviation, {"mergeNormalDeviation",
                             "Merge consecutive segments of a contour polyline while the original vertices stay within "
                             "this x d of the merged segment along the surface normal (0: no merging)",
                             closedRange(0, 1e6)});
  v(o.mergeTangentDeviation, {"mergeTangentDeviation", "Merging: largest deviation across the merged segment within the surface, x d",
                              closedRange(0, 1e6)});
  v(o.mergeAngle, {"mergeAngle", "Merging: largest angle between merged and original normals, degrees", belowRange(0, 90)});
  v(o.mergeStripAngle, {"mergeStripAngle", "Merging, smooth models: largest tilt of the merged strip's plane from the original ones, degrees",
                        belowRange(0, 90)});
  v(o.mergeMaxPieces, {"mergeMaxPieces", "Merging: most original segments in one merged segment (1: no merging)",
                       closedRange(1, 1024)});
  v(o.pointsBelow, {"pointsBelow", "Turn segments shorter than LEN (object units) into points: hybrid model (0 = none)",
                    closedRange(0, 1e30)});
  v(o.allPoints, {"allPoints", "Turn every segment into ceil(l/d)+1 points: pure point model (Table 5)"});
}

/// A mesh of the MLS surface, thesis §9.1.
template <typename V>
void describeOptions(MeshOptions& o, V&& v) {
  v.group("mesh", "Mesh of the MLS surface (§9.1)");
  v(o.cellScale, {"cellScale", "Grid cell edge, median spacings (at most 0.4 x --support-scale)", closedRange(0.25, 4),
                  kUseCliPython, "--cell"});
  v(o.mls.supportScale, {"supportScale", "MLS kernel support h, spacings", closedRange(1.5, 10)});
  v(o.mls.robust, {"robust", "RIMLS (beyond the thesis): refit the surface with robust weights, keeping creases sharp"});
  v(o.minWeight, {"minWeight", "Grid corners whose sources' weights sum below this x spacing^2 are out of reach",
                  closedRange(0, 1)});
  v(o.project, {"project", "One Newton step from each interpolated vertex onto the surface"});
}

/// The surface error of an extraction (surface/surface_error.h; beyond the thesis, §9.1's question).
template <typename V>
void describeOptions(SurfaceErrorOptions& o, V&& v) {
  v.group("surface error", "Surface error: the model's MLS surface against the input's (§9.1)");
  v(o.samples, {"samples", "Surface error: samples each way (input points, model primitives), at most; more are strided",
                closedRange(100, 1e8)});
  v(o.mls.supportScale, {"supportScale", "Surface error: MLS kernel support h, spacings", closedRange(1.5, 10)});
}

}  // namespace linesurf
