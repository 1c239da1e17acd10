#pragma once
/// Basic math types shared by every module: Eigen fixed-size vectors in single precision for
/// model data (positions, normals, colours), double where a computation needs it.
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace linesurf {

using Vec2f = Eigen::Vector2f;
using Vec3f = Eigen::Vector3f;
using Vec4f = Eigen::Vector4f;
using Vec2d = Eigen::Vector2d;
using Vec3d = Eigen::Vector3d;
using Mat3f = Eigen::Matrix3f;
using Mat3d = Eigen::Matrix3d;
using Mat4f = Eigen::Matrix4f;
using Mat4d = Eigen::Matrix4d;

/// Linear RGBA colour, each channel in [0, 1]; alpha 1 is opaque.
using Color = Eigen::Vector4f;

/// Axis-aligned bounding box; empty when min > max.
struct Bounds3f {
  Vec3f min = Vec3f::Constant(std::numeric_limits<float>::infinity());
  Vec3f max = Vec3f::Constant(-std::numeric_limits<float>::infinity());
  void extend(const Vec3f& p) { min = min.cwiseMin(p); max = max.cwiseMax(p); }
  bool empty() const { return (min.array() > max.array()).any(); }
  Vec3f center() const { return 0.5f * (min + max); }
  Vec3f diagonal() const { return max - min; }
};

}  // namespace linesurf
