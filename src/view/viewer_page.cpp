// The self-contained WebGL2 viewer page (see viewer_page.h; the page itself is web/viewer.html and web/modules/).
#include "linesurf/view/viewer_page.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <type_traits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/pipeline/option_tables.h"
#include "linesurf/render/camera.h"
#include "linesurf/web_assets.h"
#include "render/splat_rules.h"  // kMaxStretch, kMinFacing: the page's shaders must cut and cull alike

namespace linesurf {

namespace {

using json = nlohmann::json;

// The binary part of the page: arrays appended one after the other, each 4-byte aligned.
class Blob {
 public:
  template <class T>
  json add(const std::vector<T>& values, const char* type, int components) {
    while (bytes_.size() % 4) bytes_.push_back(0);
    const size_t offset = bytes_.size();
    bytes_.resize(offset + values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(bytes_.data() + offset, values.data(), values.size() * sizeof(T));
    return {{"offset", offset}, {"type", type}, {"components", components}};
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

std::string base64(const std::vector<uint8_t>& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = uint32_t(in[i]) << 16 | uint32_t(in[i + 1]) << 8 | in[i + 2];
    out += k[v >> 18];
    out += k[(v >> 12) & 63];
    out += k[(v >> 6) & 63];
    out += k[v & 63];
  }
  if (i < in.size()) {
    const uint32_t v = uint32_t(in[i]) << 16 | (i + 1 < in.size() ? uint32_t(in[i + 1]) << 8 : 0u);
    out += k[v >> 18];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

int16_t snorm16(float v) { return int16_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f)); }
uint8_t unorm8(float v) { return uint8_t(std::lround(std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) * 255.0f)); }

bool finite(const Vec3f& v) { return v.allFinite(); }

json vec(const Vec3f& v) { return json::array({v.x(), v.y(), v.z()}); }
json rgb(const Color& c) { return json::array({c.x(), c.y(), c.z()}); }
json rgba(const Color& c) { return json::array({c.x(), c.y(), c.z(), c.w()}); }

// The page's defaults: every field the option tables mark kUseViewer, by its C++ name, from the
// options given (their defaults unless the caller changed them).
class ViewerDefaults {
 public:
  json out = json::object();
  void group(const char*, const char*) {}
  template <typename T>
  void operator()(T&& value, const OptionSpec& s) {
    using U = std::remove_cvref_t<T>;
    if (!(s.use & kUseViewer)) return;
    if constexpr (std::is_arithmetic_v<U>) out[s.name] = value;
    else if constexpr (std::is_same_v<U, std::optional<float>>) out[s.name] = value.value_or(defaultZThreshold(ZThresholdMode::PerPrimitive));
    else if constexpr (std::is_same_v<U, Vec3f>) out[s.name] = vec(value);
    else if constexpr (std::is_same_v<U, AxisRef>) out[s.name] = vec(value.axis.normalized());
    else if constexpr (std::is_same_v<U, RgbRef>) out[s.name] = rgb(value.color);
    else if constexpr (std::is_same_v<U, BackgroundRef>) out[s.name] = rgba(value.color);
    else throw Error(Error::Kind::BadParameter, s.name, "", "the viewer page cannot take this option");
  }
};

json viewerDefaults(const ViewerPageOptions& o) {
  ViewerDefaults d;
  ViewOptions view = o.view;
  RenderOptions render = o.render;
  // The page always blends by each primitive's own depth extent (PerPrimitive).
  if (render.zThresholdMode != ZThresholdMode::PerPrimitive || !render.zThreshold)
    render.zThreshold = defaultZThreshold(ZThresholdMode::PerPrimitive);
  describeOptions(view, d);
  describeOptions(render, d);
  return d.out;
}

// Replaces the one occurrence of `marker` in `page` by `text`.
void fill(std::string& page, const std::string& marker, const std::string& text) {
  const size_t at = page.find(marker);
  if (at == std::string::npos) throw Error(Error::Kind::Io, "web/viewer.html", "", "template lacks " + marker);
  page.replace(at, marker.size(), text);
}

// The template filled with the page's description and its base64 data.
std::string assemblePage(const json& meta, const std::string& data) {
  std::string metaText = meta.dump();
  // JSON inside <script>: "</" would end the element early.
  for (size_t at = 0; (at = metaText.find("</", at)) != std::string::npos; at += 3) metaText.replace(at, 2, "<\\/");
  std::string page(web::kViewerHtml);
  // From the end of the template backwards, so that no inserted text is searched for a marker.
  fill(page, "@VIEWER_JS@", std::string(web::kViewerJs));
  fill(page, "@DATA@", data);
  fill(page, "@META@", metaText);
  return page;
}

json constants() {
  return {{"maxStretch", detail::kMaxStretch}, {"minFacing", detail::kMinFacing}, {"maxPointMass", kMaxPointMass}};
}

}  // namespace

std::string viewerPage(const HybridModel& model, const ViewerPageOptions& o, ViewerPageStats* statsOut) {
  validate(o.render);
  validate(o.view);
  if (o.maxPrimitives < 1) throwBadParameter("maxPrimitives", "must be >= 1");
  const size_t total = model.points.size() + model.segments.size();
  if (total > o.maxPrimitives)
    throw Error(Error::Kind::BadInput, o.name, "view",
                std::to_string(total) + " primitives exceed the viewer's budget of " + std::to_string(o.maxPrimitives) +
                    " (render it with `linesurf render`, or thin it first)");

  ViewerPageStats st;
  const BoundingSphere sphere = boundingSphere(model);
  const Vec3f centre = sphere.center;
  const float invR = 1.0f / sphere.radius;
  // Positions are stored relative to the bounding sphere (centre 0, radius 1): float32 keeps its
  // precision for models far from the origin, and the shaders work in units near 1.
  auto local = [&](const Vec3f& p) { return Vec3f((p - centre) * invR); };
  const bool clusters = model.pointProperties.count("cluster") > 0 &&
                        model.pointProperties.at("cluster").size() == model.points.size();
  // per-point shading normals: used exactly when `linesurf render` uses them (Renderer)
  const bool shading = model.attributes.shadingNormals && model.pointShadingNormals.size() == model.points.size();
  // point masses: used exactly when the Renderer uses them
  const std::vector<float>* masses = pointMasses(model);

  Blob blob;
  json meta = {{"format", "linesurf-view"}, {"version", 1}, {"name", o.name}};
  {
    std::vector<float> pos, rad, cluster, mass;
    std::vector<int16_t> nrm, snrm;
    std::vector<uint8_t> col;
    for (size_t i = 0; i < model.points.size(); ++i) {
      const Point& p = model.points[i];
      if (!finite(p.position) || !finite(p.normal) || !(p.radius > 0) || !std::isfinite(p.radius)) {
        ++st.skippedPoints;
        continue;
      }
      const Vec3f q = local(p.position);
      pos.insert(pos.end(), {q.x(), q.y(), q.z()});
      const float nn = p.normal.norm();
      const Vec3f n = nn > 0 ? Vec3f(p.normal / nn) : Vec3f::Zero();
      nrm.insert(nrm.end(), {snorm16(n.x()), snorm16(n.y()), snorm16(n.z())});
      if (shading) {  // unit, or zero where unusable: the page then lights by the plane (as preparePoint)
        const Vec3f& sn = model.pointShadingNormals[i];
        const float sl = sn.norm();
        const Vec3f m = sl > 0 && std::isfinite(sl) ? Vec3f(sn / sl) : Vec3f::Zero();
        snrm.insert(snrm.end(), {snorm16(m.x()), snorm16(m.y()), snorm16(m.z())});
      }
      rad.push_back(p.radius * invR);
      if (masses) mass.push_back(validPointMass((*masses)[i]) ? (*masses)[i] : 1.0f);
      if (model.attributes.colors)
        col.insert(col.end(), {unorm8(p.color.x()), unorm8(p.color.y()), unorm8(p.color.z()), unorm8(p.color.w())});
      if (clusters) {
        const float c = model.pointProperties.at("cluster")[i];
        cluster.push_back(std::isfinite(c) && c >= 0 && c < 16777216.0f ? std::floor(c) : -1.0f);
      }
    }
    st.points = rad.size();
    if (st.points) {
      json pts = {{"count", st.points},
                  {"position", blob.add(pos, "f32", 3)},
                  {"normal", blob.add(nrm, "i16", 3)},
                  {"radius", blob.add(rad, "f32", 1)}};
      if (shading) pts["shadingNormal"] = blob.add(snrm, "i16", 3);
      if (model.attributes.colors) pts["color"] = blob.add(col, "u8", 4);
      if (clusters) pts["cluster"] = blob.add(cluster, "f32", 1);
      if (masses) pts["mass"] = blob.add(mass, "f32", 1);
      meta["points"] = pts;
    }
  }
  {
    std::vector<float> p0, p1, rad;
    std::vector<int16_t> nrm, n0, n1;
    std::vector<uint8_t> col;
    const bool ends = model.attributes.endpointNormals;
    auto unit = [](const Vec3f& v) {
      const float n = v.norm();
      return n > 0 && std::isfinite(n) ? Vec3f(v / n) : Vec3f::Zero();
    };
    for (const Segment& s : model.segments) {
      if (!finite(s.p0) || !finite(s.p1) || !finite(s.normal) || !(s.radius > 0) || !std::isfinite(s.radius) ||
          !((s.p1 - s.p0).norm() > 0)) {
        ++st.skippedSegments;
        continue;
      }
      const Vec3f a = local(s.p0), b = local(s.p1);
      // a smooth segment without a plane normal lies in the plane of its mean endpoint normal (as
      // prepareSegment)
      const bool smooth = ends && unit(s.normal0).squaredNorm() > 0 && unit(s.normal1).squaredNorm() > 0;
      const Vec3f n = unit(smooth && !(s.normal.squaredNorm() > 0) ? Vec3f(s.normal0 + s.normal1) : s.normal);
      p0.insert(p0.end(), {a.x(), a.y(), a.z()});
      p1.insert(p1.end(), {b.x(), b.y(), b.z()});
      nrm.insert(nrm.end(), {snorm16(n.x()), snorm16(n.y()), snorm16(n.z())});
      if (ends) {
        const Vec3f e0 = unit(s.normal0), e1 = unit(s.normal1);
        n0.insert(n0.end(), {snorm16(e0.x()), snorm16(e0.y()), snorm16(e0.z())});
        n1.insert(n1.end(), {snorm16(e1.x()), snorm16(e1.y()), snorm16(e1.z())});
      }
      rad.push_back(s.radius * invR);
      if (model.attributes.colors)
        col.insert(col.end(), {unorm8(s.color.x()), unorm8(s.color.y()), unorm8(s.color.z()), unorm8(s.color.w())});
    }
    st.segments = rad.size();
    if (st.segments) {
      json segs = {{"count", st.segments},
                   {"p0", blob.add(p0, "f32", 3)},
                   {"p1", blob.add(p1, "f32", 3)},
                   {"normal", blob.add(nrm, "i16", 3)},
                   {"radius", blob.add(rad, "f32", 1)}};
      if (ends) {
        segs["normal0"] = blob.add(n0, "i16", 3);
        segs["normal1"] = blob.add(n1, "i16", 3);
      }
      if (model.attributes.colors) segs["color"] = blob.add(col, "u8", 4);
      meta["segments"] = segs;
    }
  }
  if (st.points + st.segments == 0)
    throw Error(Error::Kind::BadInput, o.name, "view",
                "nothing to draw: no point or segment with finite coordinates and a positive radius");

  meta["bytes"] = blob.bytes().size();
  meta["sphere"] = {{"center", vec(centre)}, {"radius", sphere.radius}};
  meta["renderArguments"] = o.renderArguments;
  meta["skipped"] = {{"points", st.skippedPoints}, {"segments", st.skippedSegments}};
  meta["defaults"] = viewerDefaults(o);
  meta["constants"] = constants();
  std::string page = assemblePage(meta, base64(blob.bytes()));
  st.bytes = page.size();
  if (statsOut) *statsOut = st;
  return page;
}

std::string lodViewerPage(const lod::LodHeader& h, const LodPageSource& source, const ViewerPageOptions& o) {
  validate(o.render);
  validate(o.view);
  if (source.budget < 1) throwBadParameter("budget", "must be >= 1");
  lod::validateHeader(h, o.name);  // what every reader of a hierarchy checks
  const Attributes& a = h.attributes;
  json meta = {{"format", "linesurf-view"}, {"version", 1}, {"name", o.name}};
  // The hierarchy's own description: the page checks what it reads against it (the preamble's
  // id and the node table come from the file itself).
  meta["lod"] = {{"url", source.url},
                 {"bytes", source.fileBytes},
                 {"budget", source.budget},
                 {"hierarchy", fmt::format("{:016x}", h.hierarchyId)},
                 {"points", h.points},
                 {"segments", h.segments},
                 {"colors", a.colors},
                 {"shadingNormals", a.shadingNormals},
                 {"endpointNormals", a.endpointNormals}};
  meta["bytes"] = 0;
  meta["sphere"] = {{"center", vec(h.sphere.center)}, {"radius", h.sphere.radius}};
  meta["renderArguments"] = o.renderArguments;
  meta["defaults"] = viewerDefaults(o);
  meta["constants"] = constants();
  return assemblePage(meta, "");
}

ViewerPageStats writeViewerPage(const std::filesystem::path& path, const HybridModel& model,
                                const ViewerPageOptions& options) {
  ViewerPageStats st;
  const std::string page = viewerPage(model, options, &st);
  writeFileAtomically(path, page);
  return st;
}

}  // namespace linesurf
