#pragma once
/// Perspective pinhole camera of the rendering pipeline (thesis §6.2.2: model-view transform and
/// perspective projection).
///
/// Conventions (used by every rasteriser, points and segments alike):
///  - Camera space is right-handed: x right, y up, the camera looks along -z. The *depth* of a
///    camera-space point p is d = -p.z (> 0 in front of the camera); all depth buffers, z
///    thresholds and near/far planes are in these linear depth units (world units).
///  - Screen space is in pixels: x to the right, y DOWN, origin at the top-left corner of the
///    image; pixel (i, j) covers [i, i+1) x [j, j+1) and is sampled at its centre (i+0.5, j+0.5).
///  - project(p) = (cx + f * p.x / d, cy - f * p.y / d, d) with f = focalPixels().
#include <array>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/model.h"

namespace linesurf {

/// A sphere bounding a model; the orbit and spread views frame it.
struct BoundingSphere {
  Vec3f center = Vec3f::Zero();
  float radius = 0;
};

/// Bounding sphere of every point position and segment endpoint (box centre, radius to the farthest;
/// splat radii do not count, so a hybrid and its cloud get one frame). Empty model: radius 0.
BoundingSphere boundingSphere(const HybridModel& model);

class Camera {
 public:
  /// Vertical field of view of a camera nobody chose one for, degrees (ViewOptions::fov, the
  /// CLI, Python and the viewer page take their default from it).
  static constexpr float kDefaultFovY = 30.0f;
  Camera() = default;

  /// A camera at `eye` looking at `target`, `up` roughly up (need not be orthogonal to the view
  /// direction; when parallel to it a perpendicular axis is chosen). fovY in degrees, (0, 180).
  /// near/far: positive depths of the clipping planes, 0 < near < far.
  static Camera lookAt(const Vec3f& eye, const Vec3f& target, const Vec3f& up, float fovYDegrees,
                       int width, int height, float nearDepth = 0.01f, float farDepth = 1000.0f);

  /// Orbit view of a bounding sphere: azimuth about the world `up` axis, elevation towards it
  /// (degrees, [-90, 90]). With up = +y (default): azimuth 0 looks from +z towards -z, 90 from
  /// +x. For other up axes azimuth 0 looks from frontAxis(up) (up +z: from -y). distance <= 0
  /// frames the sphere: the camera backs off until the sphere fills the smaller field of view
  /// with a 5% margin. near/far hug the sphere (near = max(1e-4 d, d - 1.01 r), far = d + 1.01 r).
  static Camera orbit(const BoundingSphere& sphere, float azimuthDegrees, float elevationDegrees,
                      float distance, int width, int height, float fovYDegrees = kDefaultFovY,
                      const Vec3f& up = Vec3f(0, 1, 0));
  /// The direction azimuth 0 looks from, for a world up axis: +z for up = +-y, -y for up = +z,
  /// +y for up = -z, +z for up = +-x; for other axes a fixed perpendicular.
  static Vec3f frontAxis(const Vec3f& up);

  /// `n` view directions spread evenly over the sphere (Fibonacci lattice, deterministic),
  /// as (azimuth, elevation) in degrees; the first view is the front-most one (azimuth 0).
  static std::vector<Vec2f> spreadViewAngles(int n);
  /// `n` auto-framed orbit cameras of the sphere at spreadViewAngles(n).
  static std::vector<Camera> spreadViews(const BoundingSphere& sphere, int n, int width, int height,
                                         float fovYDegrees = kDefaultFovY, const Vec3f& up = Vec3f(0, 1, 0));

  /// Rigid transform world -> camera (rotation + translation, last row 0 0 0 1).
  const Mat4f& cameraFromWorld() const { return cameraFromWorld_; }
  /// Projective map camera -> screen: (X, Y, D, W) = M * (x, y, z, 1) gives the pixel
  /// (X / W, Y / W) and the linear depth D = W = -z (not divided).
  Mat4f screenFromCamera() const;
  /// Camera-space point -> (pixel x, pixel y, depth). Undefined for depth <= 0.
  Vec3f project(const Vec3f& pCamera) const {
    float d = -pCamera.z();
    return Vec3f(cx_ + focal_ * pCamera.x() / d, cy_ - focal_ * pCamera.y() / d, d);
  }
  /// Camera-space direction of the ray through screen position (sx, sy) (pixel units), scaled
  /// so that its depth is 1: (sx - cx) / f, -(sy - cy) / f, -1.
  Vec3f rayThrough(float sx, float sy) const {
    return Vec3f((sx - cx_) / focal_, -(sy - cy_) / focal_, -1.0f);
  }
  Vec3f toCamera(const Vec3f& pWorld) const {
    return rotation_ * pWorld + translation_;
  }
  /// World -> camera rotation (normals transform with it: the transform is rigid).
  const Mat3f& rotation() const { return rotation_; }

  /// The six frustum planes in camera space as (a, b, c, e): a point p is inside when
  /// a p.x + b p.y + c p.z + e >= 0 for all six (left, right, bottom, top, near, far).
  std::array<Vec4f, 6> frustumPlanes() const;

  int width() const { return width_; }
  int height() const { return height_; }
  float fovYDegrees() const { return fovY_; }
  float nearDepth() const { return near_; }
  float farDepth() const { return far_; }
  /// Focal length in pixels: (height / 2) / tan(fovY / 2).
  float focalPixels() const { return focal_; }
  Vec2f principalPoint() const { return Vec2f(cx_, cy_); }
  const Vec3f& eye() const { return eye_; }
  const Vec3f& target() const { return target_; }
  const Vec3f& up() const { return up_; }

  /// Same camera with another viewport size (keeps fovY; used by --size and tests).
  Camera withViewport(int width, int height) const;
  Camera withNearFar(float nearDepth, float farDepth) const;

 private:
  void update();
  Vec3f eye_ = Vec3f(0, 0, 1), target_ = Vec3f::Zero(), up_ = Vec3f(0, 1, 0);
  float fovY_ = kDefaultFovY, near_ = 0.01f, far_ = 1000.0f;
  int width_ = 512, height_ = 512;
  float focal_ = 1, cx_ = 256, cy_ = 256;
  Mat3f rotation_ = Mat3f::Identity();
  Vec3f translation_ = Vec3f::Zero();
  Mat4f cameraFromWorld_ = Mat4f::Identity();
};

}  // namespace linesurf
