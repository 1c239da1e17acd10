// linesurf info FILE [--json]: what a model file holds (kind, counts, bounds, attributes,
// average point spacing, texture), or a level-of-detail hierarchy (nodes, depth, sphere). The output is the result, so it is printed even with --quiet.
#include <fmt/format.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

#include "command.h"
#include "linesurf/geometry/noise.h"
#include "linesurf/io/model_stats.h"
#include "linesurf/lod/lod.h"

namespace linesurf::cli {
namespace {

struct InfoArgs {
  std::string file;
  bool json = false;
};

std::string vec(const Vec3f& v) { return fmt::format("{:.6g} {:.6g} {:.6g}", v.x(), v.y(), v.z()); }

/// A level-of-detail hierarchy: its header and node table (read, not its blocks), as the
/// readers (render, view, Python) see it; a damaged one is refused as they refuse it.
void runLodInfo(const InfoArgs& a) {
  checkFiles({a.file}, {}, /*inputsHeldWhole=*/false);
  const lod::LodFile f(a.file);
  const lod::LodHeader& h = f.header();
  size_t leaves = 0, depth = 0;
  uint64_t representatives = 0;
  for (const lod::NodeInfo& n : f.nodes()) {
    leaves += n.leaf;
    depth = std::max<size_t>(depth, n.level);
    if (!n.leaf) representatives += n.count();
  }
  std::error_code ec;
  const uint64_t bytes = std::filesystem::file_size(a.file, ec);
  std::string attrs;
  for (const auto& [on, name] : {std::pair{h.attributes.normals, "normals"}, {h.attributes.colors, "colors"},
                                 {h.attributes.radii, "radii"}, {h.attributes.shadingNormals, "shading-normals"},
                                 {h.attributes.endpointNormals, "endpoint-normals"}, {h.pointMasses, "masses"}})
    if (on) attrs += (attrs.empty() ? "" : " ") + std::string(name);
  const Vec3f& c = h.sphere.center;
  if (a.json) {
    nlohmann::json j = {{"path", a.file},
                        {"kind", "hierarchy"},
                        {"hierarchy", fmt::format("{:016x}", h.hierarchyId)},
                        {"points", h.points},
                        {"segments", h.segments},
                        {"nodes", f.nodes().size()},
                        {"leaves", leaves},
                        {"depth", depth},
                        {"representatives", representatives},
                        {"sphere", {{"center", {c.x(), c.y(), c.z()}}, {"radius", h.sphere.radius}}},
                        {"properties", attrs},
                        {"leafSize", h.options.leafSize},
                        {"grid", h.options.grid},
                        {"bytes", bytes}};
    std::puts(j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
    return;
  }
  std::string out = a.file + "\n";
  out += fmt::format("  kind:       level-of-detail hierarchy {:016x}\n", h.hierarchyId);
  out += fmt::format("  points:     {}\n  segments:   {}\n", h.points, h.segments);
  out += fmt::format("  nodes:      {} ({} leaves), depth {}, {} representatives in the inner nodes\n", f.nodes().size(),
                     leaves, depth, representatives);
  out += fmt::format("  sphere:     centre {}  radius {:.6g} (the rendering frame)\n", vec(c), h.sphere.radius);
  out += fmt::format("  properties: {}\n", attrs.empty() ? "(positions only)" : attrs);
  out += fmt::format("  built:      leaf size {}, grid {}; {:.1f} MB\n", h.options.leafSize, h.options.grid, double(bytes) / 1e6);
  std::fputs(out.c_str(), stdout);
}

void runInfo(const InfoArgs& a) {
  if (lod::isLodFile(a.file)) return runLodInfo(a);
  checkFiles({a.file}, {});  // reading it fits the budget
  std::vector<Vec3f> positions;
  const ModelSummary s = summarizeFile(a.file, &positions);
  const bool emptyBounds = s.bounds.empty();
  // A scan's noise along its normals, against which the extractions' epsilon means something.
  const NoiseEstimate noise = s.kind == "points" ? estimateNoise(positions) : NoiseEstimate{};
  const double noiseRelative = s.averageSpacing > 0 ? noise.sigma / s.averageSpacing : 0.0;
  if (a.json) {
    nlohmann::json j;
    j["path"] = a.file;
    j["kind"] = s.kind;
    if (s.kind == "mesh") {
      j["vertices"] = s.vertices;
      j["faces"] = s.faces;
    } else {
      j["points"] = s.points;
      j["segments"] = s.segments;
    }
    if (emptyBounds) {
      j["bounds"] = nullptr;
    } else {
      j["bounds"] = {{"min", {s.bounds.min.x(), s.bounds.min.y(), s.bounds.min.z()}},
                     {"max", {s.bounds.max.x(), s.bounds.max.y(), s.bounds.max.z()}},
                     {"diagonal", s.bounds.diagonal().norm()}};
    }
    j["properties"] = s.properties;
    j["averageSpacing"] = s.averageSpacing;
    if (s.radiusMax > 0)
      j["radii"] = {{"min", s.radiusMin}, {"median", s.radiusMedian}, {"max", s.radiusMax}, {"above10xMedian", s.radiiAbove10xMedian}};
    else j["radii"] = nullptr;
    if (noise.fitted > 0)
      j["noise"] = {{"sigma", noise.sigma}, {"relativeToSpacing", noiseRelative},
                    {"quartiles", {noise.lowerQuartile, noise.upperQuartile}}, {"samples", noise.fitted}};
    else j["noise"] = nullptr;
    if (s.textureWidth > 0) j["texture"] = {{"width", s.textureWidth}, {"height", s.textureHeight}};
    else j["texture"] = nullptr;
    j["comments"] = s.comments;
    // Paths and comments are bytes, not always UTF-8: bytes that are not become U+FFFD rather
    // than failing the whole report.
    std::puts(j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
    return;
  }
  std::string out = a.file + "\n";
  out += fmt::format("  kind:       {}\n", s.kind);
  if (s.kind == "mesh") out += fmt::format("  vertices:   {}\n  faces:      {}\n", s.vertices, s.faces);
  else out += fmt::format("  points:     {}\n  segments:   {}\n", s.points, s.segments);
  if (emptyBounds) out += "  bounds:     (empty)\n";
  else
    out += fmt::format("  bounds:     min {}  max {}  (diagonal {:.6g})\n", vec(s.bounds.min), vec(s.bounds.max),
                       s.bounds.diagonal().norm());
  std::string props;
  for (const auto& p : s.properties) props += (props.empty() ? "" : " ") + p;
  out += fmt::format("  properties: {}\n", props.empty() ? "(positions only)" : props);
  out += fmt::format("  spacing:    {:.6g} (mean nearest-neighbour distance)\n", s.averageSpacing);
  if (s.radiusMax > 0)
    out += fmt::format("  radii:      min {:.6g}  median {:.6g}  max {:.6g} ({:.1f} x the median); {} above 10 x the median\n",
                       s.radiusMin, s.radiusMedian, s.radiusMax, s.radiusMax / s.radiusMedian, s.radiiAbove10xMedian);
  if (noise.fitted > 0)
    out += fmt::format("  noise:      sigma {:.6g} ({:.3f} x the spacing) along the normals; quartiles {:.3g} .. {:.3g} over {} samples\n",
                       noise.sigma, noiseRelative, noise.lowerQuartile, noise.upperQuartile, noise.fitted);
  if (s.textureWidth > 0) out += fmt::format("  texture:    {}x{}\n", s.textureWidth, s.textureHeight);
  else out += "  texture:    none\n";
  for (const auto& c : s.comments) out += fmt::format("  comment:    {}\n", c);
  std::fputs(out.c_str(), stdout);
}

RegisterCommand reg(10, [](CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "Show what a model file holds (kind, counts, bounds, attributes, spacing)");
  sub->add_option("file", args->file, "Model file (.ply, .obj, .xyz) or hierarchy (.lod)")->type_name("FILE")->required();
  sub->add_flag("--json", args->json, "Print JSON instead of text");
  sub->callback([args] { runInfo(*args); });
});

}  // namespace
}  // namespace linesurf::cli
