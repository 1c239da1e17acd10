#pragma once
/// `linesurf view`: one self-contained HTML page that draws a point, segment or hybrid model with
/// WebGL2 on the GPU (GPU line-segment splatting, the future work of thesis §9.3). The page holds
/// the model (base64 of float32 / int16 / uint8 arrays), the viewer's JavaScript and GLSL
/// (web/modules/, bundled into one script at build time), and needs no network access and no
/// server: it opens from file://.
///
/// The page draws what `linesurf render` draws, with the same conventions (camera.h) and the same
/// defaults (render_options.h): object-space EWA point splats (§4.2.2) and line-segment splats
/// (§5, the closed form in erf of the ScreenSpace method), depth-tolerant blending with
/// normalisation (the two-pass visibility + accumulation of Botsch et al. 2005 standing in for
/// Z^3, §6.2.3), per-pixel Phong lighting (§6.2.2). Points with shading normals
/// (HybridModel::pointShadingNormals) are lit by them, segments with endpoint normals by
/// normalize(n0 + u (n1 - n0)), as `linesurf render` does. See docs/decisions.md
/// "Viewer (`linesurf view`)".
#include <cstddef>
#include <filesystem>
#include <string>

#include "linesurf/core/model.h"
#include "linesurf/lod/lod.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/render_options.h"

namespace linesurf {

struct ViewerPageOptions {
  /// Shown in the page's title and panel (e.g. the model's file name); also the PATH of errors.
  std::string name;
  /// Largest number of points + segments a page may hold, >= 1. Default 5 M: about 110 MB of
  /// base64 and 200 MB of GPU buffers; larger models are refused (Error BadInput).
  size_t maxPrimitives = 5'000'000;
  /// Appended to the `linesurf render` arguments the page shows (e.g. "--primitive points" for a
  /// mesh drawn as its vertices).
  std::string renderArguments;
  /// The page's default orbit view: azimuth, elevation, fov and the world up axis (also the
  /// turntable's); the page's own controls replace the rest.
  ViewOptions view;
  /// Filtering, z threshold (PerPrimitive mode), material, light (headlight), default colour and
  /// background of the page; the page always lights per pixel and culls back faces. Which fields
  /// the page takes is the option table's (pipeline/option_tables.h, kUseViewer).
  RenderOptions render;
};

/// Counts of what went into a page.
struct ViewerPageStats {
  size_t points = 0, segments = 0;        ///< embedded
  size_t skippedPoints = 0, skippedSegments = 0;  ///< non-finite or zero-radius: never drawn
  size_t bytes = 0;                       ///< size of the page
};

/// The page for `model`, whose points and segments must carry normals and radii (the CLI runs the
/// geometry stage, §6.1, first; a zero normal is drawn facing the viewer). Primitives with
/// non-finite coordinates or a radius <= 0 are left out and counted.
/// Throws linesurf::Error: BadInput (path = options.name) when the model holds more than
/// options.maxPrimitives primitives or nothing drawable; BadParameter for absurd options.
std::string viewerPage(const HybridModel& model, const ViewerPageOptions& options = {},
                       ViewerPageStats* stats = nullptr);

/// The page in level-of-detail mode (`linesurf view MODEL.lod`): it embeds no primitives but
/// reads the hierarchy `header` describes from `url` (served over HTTP with Range support) node
/// block by node block, choosing its nodes for each view as lod::selectNodes does within a splat
/// budget (initially `budget`, >= 1; the page's control changes it). See docs/file-format.md,
/// "How the viewer reads a hierarchy over HTTP". Throws BadParameter for absurd options.
struct LodPageSource {
  std::string url = "/model.lod";
  uint64_t fileBytes = 0;  ///< size of the .lod file (shown in the panel)
  uint64_t budget = 1'000'000;
};
std::string lodViewerPage(const lod::LodHeader& header, const LodPageSource& source,
                          const ViewerPageOptions& options = {});

/// viewerPage() written atomically to `path` (no half-written file on failure).
ViewerPageStats writeViewerPage(const std::filesystem::path& path, const HybridModel& model,
                                const ViewerPageOptions& options = {});

}  // namespace linesurf
