#pragma once
/// Drawings from a model's own segments (thesis §9.4, §9.5): the segments drawn as ink strokes
/// of constant screen width over paper, with the hidden parts removed by the splat depth buffer,
/// density driven by the shaded render's tone, and silhouettes from the depth and normal buffers.
///
///  - Strokes (§9.4): segments that share an endpoint (bit-equal: contour lines do) are chained
///    into one polyline stroke; an isolated segment (a shape-approximation strip) is a stroke.
///  - Nested priorities, assigned once in object space (StrokeSet): strokes are ranked by a
///    nested sampling of the surface (every level keeps the strokes of the coarser ones and adds
///    those farther than its radius from all kept so far, radii halving), and each stroke's
///    priority is the share of the model's stroke length ranked before it. Drawing the strokes
///    of priority below f draws about the fraction f of the stroke length, evenly spread; a
///    pixel of darkness D draws a stroke where its priority is below D x (projected spacing) /
///    width, so a darker tone adds strokes and never moves one, and strokes stay on the surface
///    as the camera moves (Praun et al. 2001's nesting, on the model's own lines).
///  - In-between strokes: where even every stroke is lighter than the tone, copies of the
///    strokes moved half their spacing across (n x t, on the tangent plane: within (s/2)^2 k / 2
///    of the surface) double the density, in the strokes' own priority order.
///  - A second family across the first (cross hatching, Hertzmann & Zorin 2000): short strokes
///    along n x t through the main strokes, one main spacing long, drawn only where the main
///    family at full density is lighter than the tone; their priorities nest along each main
///    stroke (a van der Corput order), so a darker tone adds cross strokes between the drawn ones.
///  - Hidden strokes: the splat depth buffer of the same view (points and segments) is rendered
///    first; a stroke sample is visible where its depth lies within strokeDepthTolerance x its
///    segment's radius of the visible surface's.
///  - Silhouettes (§9.5): boundaries between neighbouring pixels where the coverage changes, the
///    depth jumps, or n.v changes sign, chained into polylines and drawn as strokes.
/// Everything is drawn from visible runs (Drawing::runs), which the SVG writer writes as paths:
/// the raster and the vector output show the same strokes. Identical for any thread count.
#include <cstdint>
#include <memory>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"
#include "linesurf/core/model.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/renderer.h"
#include "linesurf/render/stroke_run.h"

namespace linesurf {

/// What `render` draws.
enum class DrawStyle {
  Splat,  ///< the shaded EWA splatting of §6.2 (the default)
  Lines,  ///< every visible segment as an ink stroke, with silhouettes
  Hatch,  ///< strokes whose density follows the shaded tone (§9.4), cross family, silhouettes
};

struct DrawingOptions {
  DrawStyle style = DrawStyle::Splat;
  /// Width of every stroke, pixels, [0.1, 64]: constant on screen.
  float strokeWidth = 1.25f;
  Color paper = Color(1, 1, 1, 1);  ///< shown where no ink is; alpha < 1 gives a transparent PNG
  Color ink = Color(0, 0, 0, 1);    ///< stroke colour, alpha > 0
  /// Hatch: the shaded luminance is quantised to this many tones before it sets the density, so
  /// that strokes end on a few tone boundaries instead of flickering on every shading change;
  /// [0, 256], 0 = continuous.
  int toneLevels = 8;
  /// A stroke sample is visible where its depth is within this multiple of its segment's radius
  /// of the splat depth buffer (the strip's own depth spread at grazing views), (0, 100].
  float strokeDepthTolerance = 2.0f;
  bool silhouettes = true;  ///< draw silhouettes (depth and normal buffers)
  bool inBetween = true;    ///< Hatch: copies of the strokes halfway across where they are too few
  bool crossHatch = true;   ///< Hatch: the second family in tones the first cannot reach
  /// Seed of the order of the strokes within one level of the nested sampling (object space).
  uint64_t strokeSeed = 1;
};

/// Throws OptionError naming the first absurd field.
void validate(const DrawingOptions& options);

struct DrawingStats {
  size_t strokes = 0;        ///< strokes of the model (main family)
  size_t inBetweenStrokes = 0;  ///< copies of the main strokes halfway across
  size_t crossStrokes = 0;   ///< strokes of the cross family
  size_t strokesDrawn = 0;   ///< strokes with a visible run (both families)
  size_t runs = 0;           ///< visible runs, silhouettes excluded
  size_t silhouettePaths = 0;
  double splatSeconds = 0, strokeSeconds = 0, rasterSeconds = 0, totalSeconds = 0;
};

struct Drawing {
  Image image;                    ///< ink over paper, RGBA
  std::vector<StrokeRun> runs;    ///< visible runs: the strokes', then the silhouettes'
  /// Visible length of every stroke in pixels (StrokeSet order; 0: not drawn): which strokes a
  /// view draws, for coherence between views.
  std::vector<float> visibleLength;
  /// The splat render the tone and depth came from (DrawingRenderer; with its depth and normal
  /// buffers and counters).
  RenderResult splat;
  DrawingStats stats;
};

/// The object-space strokes of a model and their nested priorities (§9.4), built once.
class StrokeSet {
 public:
  /// One straight piece of a stroke.
  struct Piece {
    Vec3f a, b;         ///< endpoints, object space, in stroke order
    Vec3f normal;       ///< the segment's normal
    float radius;       ///< the segment's half-width (depth tolerance)
    float spacing;      ///< distance to the neighbouring strokes across (object units)
    float crossSpacing; ///< cross family: the main family's spacing where it crosses (others 0)
  };
  struct Stroke {
    uint32_t first = 0, count = 0;  ///< pieces
    float priority = 0;             ///< (0, 1]: share of the family's length ranked up to it
    uint8_t family = 0;             ///< kMain, kCross or kInBetween
    static constexpr uint8_t kMain = 0, kCross = 1, kInBetween = 2;
  };
  /// Chains, spacings, cross strokes and priorities of `model`'s segments (none: an empty set).
  StrokeSet(const HybridModel& model, const DrawingOptions& options);
  const std::vector<Stroke>& strokes() const { return strokes_; }
  const std::vector<Piece>& pieces() const { return pieces_; }
  size_t mainStrokes() const { return mainStrokes_; }
  size_t inBetweenStrokes() const { return inBetween_; }
  /// The typical spacing between neighbouring strokes (median over the pieces), object units.
  float typicalSpacing() const { return typicalSpacing_; }

 private:
  std::vector<Stroke> strokes_;
  std::vector<Piece> pieces_;
  size_t mainStrokes_ = 0, inBetween_ = 0;
  float typicalSpacing_ = 0;
};

/// Draws one view from a splat render of it (with depth and normal buffers).
Drawing drawStrokes(const StrokeSet& strokes, const Camera& camera, const RenderResult& splat,
                    const DrawingOptions& options);

/// A model drawn in a style other than Splat: the Renderer (depth and normal buffers on) and
/// the StrokeSet, made once; then any number of views. Keeps a reference to `model`.
class DrawingRenderer {
 public:
  DrawingRenderer(const HybridModel& model, const RenderOptions& render, const DrawingOptions& drawing);
  Drawing render(const Camera& camera) const;
  const BoundingSphere& sphere() const { return renderer_.sphere(); }
  const StrokeSet& strokes() const { return strokes_; }

 private:
  static RenderOptions withBuffers(RenderOptions o);
  Renderer renderer_;
  DrawingOptions options_;
  StrokeSet strokes_;
};

/// The shaded tone a drawing follows at a pixel of colour c: Rec. 709 luminance quantised to
/// `levels` tones, each the centre of its bin ((i + 0.5) / levels); levels 0: unquantised.
float drawingTone(const Color& c, int levels);

/// The drawing as an SVG document of `width` x `height` pixels (user units = pixels): the paper
/// as a rectangle, then every visible run as one path (stroke width in pixels, round caps).
std::string drawingSvg(const Drawing& drawing, const DrawingOptions& options);

}  // namespace linesurf
