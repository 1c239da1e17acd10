// One validation of models and meshes after reading and before writing (model_validate.h).
#include "linesurf/io/model_validate.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace linesurf {

namespace {

constexpr float kMax = std::numeric_limits<float>::max();
/// Shading normals must be unit within this (ascii files with 4 digits are within 1e-3).
constexpr float kUnitTolerance = 0.01f;

struct Checker {
  const std::string& name;
  Error::Kind kind;
  [[noreturn]] void fail(const std::string& where, const std::string& what) const { throw Error(kind, name, where, what); }
  void finite(float v, const char* element, size_t i, const char* what) const {
    if (!std::isfinite(v)) fail(fmt::format("element {} {}", element, i), fmt::format("{} {} is not finite", what, v));
  }
  template <class V>
  void finiteVec(const V& v, const char* element, size_t i, const char* what) const {
    for (int c = 0; c < int(v.size()); ++c)
      if (!std::isfinite(v[c]))
        fail(fmt::format("element {} {}", element, i), fmt::format("{} has a non-finite component ({})", what, v[c]));
  }
  void unit(const Color& c, const char* element, size_t i) const {
    static const char* names[4] = {"red", "green", "blue", "alpha"};
    for (int k = 0; k < 4; ++k)
      if (!(c[k] >= 0.0f && c[k] <= 1.0f))
        fail(fmt::format("element {} {}", element, i), fmt::format("{} {:g} outside [0, 1]", names[k], c[k]));
  }
  void radius(float r, const char* element, size_t i) const {
    // 0 = unknown (estimated later); anything else must be a positive finite length.
    if (r == 0.0f) return;
    if (!(r > 0.0f) || !(r <= kMax))
      fail(fmt::format("element {} {}", element, i), fmt::format("radius {:g} is not a positive finite length", r));
  }
};

}  // namespace

void validateModel(const HybridModel& m, const std::string& name, Error::Kind kind) {
  const Checker c{name, kind};
  bool anyPointRadius = false, anySegmentRadius = false;
  for (size_t i = 0; i < m.points.size(); ++i) {
    const Point& p = m.points[i];
    c.finiteVec(p.position, "vertex", i, "position");
    c.finiteVec(p.normal, "vertex", i, "normal");
    c.unit(p.color, "vertex", i);
    c.radius(p.radius, "vertex", i);
    anyPointRadius = anyPointRadius || p.radius > 0;
  }
  if (m.attributes.shadingNormals) {  // unit shading normals, one per point
    if (m.pointShadingNormals.size() != m.points.size())
      c.fail("shading normals", fmt::format("{} shading normals for {} points", m.pointShadingNormals.size(), m.points.size()));
    for (size_t i = 0; i < m.points.size(); ++i) {
      const Vec3f& n = m.pointShadingNormals[i];
      c.finiteVec(n, "vertex", i, "shading normal");
      if (const float len = n.norm(); !(std::abs(len - 1.0f) <= kUnitTolerance))
        c.fail(fmt::format("element vertex {}", i),
               fmt::format("shading normal ({:g}, {:g}, {:g}) is not unit length (|n| = {:g})", n.x(), n.y(), n.z(), len));
    }
  }
  for (size_t i = 0; i < m.segments.size(); ++i) {
    const Segment& s = m.segments[i];
    c.finiteVec(s.p0, "segment", i, "endpoint p0");
    c.finiteVec(s.p1, "segment", i, "endpoint p1");
    c.finiteVec(s.normal, "segment", i, "normal");
    c.finiteVec(s.normal0, "segment", i, "normal at p0");
    c.finiteVec(s.normal1, "segment", i, "normal at p1");
    c.finiteVec(s.uv0, "segment", i, "uv0");
    c.finiteVec(s.uv1, "segment", i, "uv1");
    c.unit(s.color, "segment", i);
    c.radius(s.radius, "segment", i);
    anySegmentRadius = anySegmentRadius || s.radius > 0;
  }
  // A radius far beyond the model's size is a unit error or garbage (it would cover any view).
  if (anyPointRadius || anySegmentRadius) {
    const float size = m.bounds().diagonal().norm();
    if (size > 0 && std::isfinite(size)) {
      const float limit = 1e3f * size;
      for (size_t i = 0; i < m.points.size(); ++i)
        if (m.points[i].radius > limit)
          c.fail(fmt::format("element vertex {}", i),
                 fmt::format("radius {:g} is more than 1000 times the model's size ({:g})", m.points[i].radius, size));
      for (size_t i = 0; i < m.segments.size(); ++i)
        if (m.segments[i].radius > limit)
          c.fail(fmt::format("element segment {}", i),
                 fmt::format("radius {:g} is more than 1000 times the model's size ({:g})", m.segments[i].radius, size));
    }
  }
  for (const auto& [prop, values] : m.pointProperties) {
    if (values.size() != m.points.size())
      c.fail("property " + prop, fmt::format("{} values for {} points", values.size(), m.points.size()));
    for (size_t i = 0; i < values.size(); ++i)
      if (!std::isfinite(values[i]))
        c.fail(fmt::format("element vertex {}", i), fmt::format("property '{}' is {} (not finite)", prop, values[i]));
    if (prop == kPointMassProperty)
      for (size_t i = 0; i < values.size(); ++i)
        if (!validPointMass(values[i]))
          c.fail(fmt::format("element vertex {}", i),
                 fmt::format("property '{}' is {:g} (a point's mass must be in (0, 1e6])", prop, values[i]));
  }
  for (const auto& [prop, values] : m.segmentProperties) {
    if (values.size() != m.segments.size())
      c.fail("property " + prop, fmt::format("{} values for {} segments", values.size(), m.segments.size()));
    for (size_t i = 0; i < values.size(); ++i)
      if (!std::isfinite(values[i]))
        c.fail(fmt::format("element segment {}", i), fmt::format("property '{}' is {} (not finite)", prop, values[i]));
  }
  if (!m.provenance.empty() && m.provenance.size() != m.segments.size())
    c.fail("provenance", fmt::format("{} lists for {} segments", m.provenance.size(), m.segments.size()));
}

void validateMesh(const TriangleMesh& m, const std::string& name, Error::Kind kind) {
  const Checker c{name, kind};
  const size_t nv = m.positions.size();
  if (!m.normals.empty() && m.normals.size() != nv)
    c.fail("normals", fmt::format("{} normals for {} vertices", m.normals.size(), nv));
  if (!m.colors.empty() && m.colors.size() != nv)
    c.fail("colors", fmt::format("{} colours for {} vertices", m.colors.size(), nv));
  if (!m.cornerUVs.empty() && m.cornerUVs.size() != m.faces.size())
    c.fail("texcoord", fmt::format("{} texture coordinate triples for {} faces", m.cornerUVs.size(), m.faces.size()));
  for (size_t i = 0; i < nv; ++i) {
    c.finiteVec(m.positions[i], "vertex", i, "position");
    if (!m.normals.empty()) c.finiteVec(m.normals[i], "vertex", i, "normal");
    if (!m.colors.empty()) c.unit(m.colors[i], "vertex", i);
  }
  for (size_t f = 0; f < m.faces.size(); ++f) {
    for (uint32_t v : m.faces[f])
      if (v >= nv) c.fail(fmt::format("element face {}", f), fmt::format("vertex index {} out of range (the mesh has {} vertices)", v, nv));
    if (!m.cornerUVs.empty())
      for (const Vec2f& uv : m.cornerUVs[f]) c.finiteVec(uv, "face", f, "texture coordinate");
  }
}

}  // namespace linesurf
