// Perspective camera, thesis §6.2.2 (model-view transform, perspective projection).
#include "linesurf/render/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "linesurf/core/error.h"

namespace linesurf {

namespace {
float radians(float deg) { return float(deg * std::numbers::pi / 180.0); }
}  // namespace

BoundingSphere boundingSphere(const HybridModel& model) {
  // The default camera frames where the surface is (positions and endpoints), not how wide its
  // splats are drawn: a hybrid extracted from a cloud keeps the cloud's extent but not its radii
  // (segments get their own, and one large kept point used to decide the frame), so a radius term
  // framed a cloud and its hybrid differently and their pictures did not line up. The orbit camera
  // leaves a 5% margin around the sphere for the splats at the silhouette.
  Bounds3f b;
  for (const Point& p : model.points)
    if (p.position.allFinite()) b.extend(p.position);
  for (const Segment& s : model.segments) {
    if (!s.p0.allFinite() || !s.p1.allFinite()) continue;
    b.extend(s.p0);
    b.extend(s.p1);
  }
  BoundingSphere sphere;
  if (b.empty()) return sphere;
  sphere.center = b.center();
  float r2 = 0, maxRadius = 0;
  for (const Point& p : model.points) {
    if (!p.position.allFinite()) continue;
    r2 = std::max(r2, (p.position - sphere.center).squaredNorm());
    if (std::isfinite(p.radius)) maxRadius = std::max(maxRadius, p.radius);
  }
  for (const Segment& s : model.segments)
    if (s.p0.allFinite() && s.p1.allFinite())
      r2 = std::max({r2, (s.p0 - sphere.center).squaredNorm(), (s.p1 - sphere.center).squaredNorm()});
  sphere.radius = std::sqrt(r2);
  // All points in one place: frame the splat itself, or a unit sphere when it has no radius.
  if (!(sphere.radius > 0)) sphere.radius = maxRadius > 0 ? maxRadius : 1.0f;
  return sphere;
}

Camera Camera::lookAt(const Vec3f& eye, const Vec3f& target, const Vec3f& up, float fovYDegrees, int width,
                      int height, float nearDepth, float farDepth) {
  if (!(fovYDegrees > 0 && fovYDegrees < 180)) throwBadParameter("fov", "must be in (0, 180) degrees");
  if (width < 1 || height < 1 || width > 32768 || height > 32768)
    throwBadParameter("size", "image size must be within 1..32768 pixels per side");
  if (!(nearDepth > 0 && farDepth > nearDepth) || !std::isfinite(farDepth))
    throwBadParameter("near/far", "need 0 < near < far < infinity");
  if (!eye.allFinite() || !target.allFinite() || !up.allFinite() || (eye - target).norm() == 0)
    throwBadParameter("look-at", "eye and target must be finite and distinct");
  Camera c;
  c.eye_ = eye;
  c.target_ = target;
  c.up_ = up;
  c.fovY_ = fovYDegrees;
  c.width_ = width;
  c.height_ = height;
  c.near_ = nearDepth;
  c.far_ = farDepth;
  c.update();
  return c;
}

void Camera::update() {
  Vec3f back = (eye_ - target_).normalized();  // camera +z
  Vec3f up = up_;
  if (up.norm() == 0 || up.normalized().cross(back).norm() < 1e-4f) {
    // up parallel to the view direction: use the world axis least aligned with it
    Vec3f a = back.cwiseAbs();
    up = a.x() <= a.y() && a.x() <= a.z() ? Vec3f::UnitX() : (a.y() <= a.z() ? Vec3f::UnitY() : Vec3f::UnitZ());
  }
  Vec3f right = up.cross(back).normalized();
  Vec3f trueUp = back.cross(right);
  rotation_.row(0) = right.transpose();
  rotation_.row(1) = trueUp.transpose();
  rotation_.row(2) = back.transpose();
  translation_ = -(rotation_ * eye_);
  cameraFromWorld_.setIdentity();
  cameraFromWorld_.topLeftCorner<3, 3>() = rotation_;
  cameraFromWorld_.topRightCorner<3, 1>() = translation_;
  focal_ = 0.5f * float(height_) / std::tan(0.5f * radians(fovY_));
  cx_ = 0.5f * float(width_);
  cy_ = 0.5f * float(height_);
}

Mat4f Camera::screenFromCamera() const {
  Mat4f m = Mat4f::Zero();
  // X = f x + cx d, Y = -f y + cy d with d = -z; D = W = d.
  m(0, 0) = focal_;
  m(0, 2) = -cx_;
  m(1, 1) = -focal_;
  m(1, 2) = -cy_;
  m(2, 2) = -1;
  m(3, 2) = -1;
  return m;
}

Vec3f Camera::frontAxis(const Vec3f& up) {
  Vec3f u = up.normalized();
  Vec3f front;
  if (std::abs(u.y()) > 0.9f) front = Vec3f::UnitZ();
  else if (u.z() > 0.9f) front = -Vec3f::UnitY();
  else if (u.z() < -0.9f) front = Vec3f::UnitY();
  else front = Vec3f::UnitZ();
  return (front - front.dot(u) * u).normalized();
}

Camera Camera::orbit(const BoundingSphere& sphere, float azimuthDegrees, float elevationDegrees, float distance,
                     int width, int height, float fovYDegrees, const Vec3f& upAxis) {
  if (!upAxis.allFinite() || upAxis.norm() == 0) throwBadParameter("up axis", "must be a finite non-zero vector");
  if (!std::isfinite(azimuthDegrees)) throwBadParameter("azimuth", "must be finite");
  if (!(elevationDegrees >= -90 && elevationDegrees <= 90)) throwBadParameter("elevation", "must be in [-90, 90] degrees");
  if (!(fovYDegrees > 0 && fovYDegrees < 180)) throwBadParameter("fov", "must be in (0, 180) degrees");
  if (width < 1 || height < 1) throwBadParameter("size", "image size must be positive");
  if (!std::isfinite(distance)) throwBadParameter("distance", "must be finite");
  float r = sphere.radius > 0 ? sphere.radius : 1.0f;
  if (distance <= 0) {
    // The sphere's silhouette fits in the half-angle of the narrower field of view, 5% margin.
    float halfY = 0.5f * radians(fovYDegrees);
    float halfX = std::atan(std::tan(halfY) * float(width) / float(height));
    float half = std::min(halfX, halfY);
    distance = 1.05f * r / std::sin(half);
  }
  float az = radians(azimuthDegrees), el = radians(elevationDegrees);
  const Vec3f U = upAxis.normalized(), F = frontAxis(U), Rt = U.cross(F);
  Vec3f dir = std::cos(el) * (std::cos(az) * F + std::sin(az) * Rt) + std::sin(el) * U;
  Vec3f eye = sphere.center + distance * dir;
  // Near/far hug the sphere so depth precision stays good; near never reaches 0.
  float nearD = std::max(1e-4f * distance, distance - 1.01f * r);
  float farD = std::max(distance + 1.01f * r, nearD * 2);
  // Looking straight down/up: the image's up is the horizontal direction away from the eye.
  Vec3f up = std::abs(elevationDegrees) > 89.9f
                 ? Vec3f(-(elevationDegrees > 0 ? 1.f : -1.f) * (std::cos(az) * F + std::sin(az) * Rt))
                 : U;
  return lookAt(eye, sphere.center, up, fovYDegrees, width, height, nearD, farD);
}

std::vector<Vec2f> Camera::spreadViewAngles(int n) {
  if (n < 1) throwBadParameter("views", "must be >= 1");
  std::vector<Vec2f> out;
  out.reserve(size_t(n));
  if (n == 1) {
    out.emplace_back(0.0f, 0.0f);
    return out;
  }
  // Fibonacci lattice on the sphere with the "y" axis up; rotated so that view 0 is azimuth 0.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    double y = 1.0 - 2.0 * (i + 0.5) / n;           // from top to bottom
    double az = std::fmod(golden * i, 2 * std::numbers::pi);
    double el = std::asin(std::clamp(y, -1.0, 1.0));
    out.emplace_back(float(az * 180.0 / std::numbers::pi), float(el * 180.0 / std::numbers::pi));
  }
  // Start with the view closest to the equator (a front view), keep the lattice order after it.
  size_t best = 0;
  for (size_t i = 1; i < out.size(); ++i)
    if (std::abs(out[i].y()) < std::abs(out[best].y())) best = i;
  std::rotate(out.begin(), out.begin() + long(best), out.end());
  float az0 = out[0].x();
  for (Vec2f& v : out) {
    float a = std::fmod(v.x() - az0, 360.0f);
    if (a < 0) a += 360.0f;
    if (a > 180.0f) a -= 360.0f;
    v.x() = a;
  }
  return out;
}

std::vector<Camera> Camera::spreadViews(const BoundingSphere& sphere, int n, int width, int height, float fovYDegrees,
                                        const Vec3f& up) {
  std::vector<Camera> cams;
  for (const Vec2f& a : spreadViewAngles(n)) cams.push_back(orbit(sphere, a.x(), a.y(), 0, width, height, fovYDegrees, up));
  return cams;
}

std::array<Vec4f, 6> Camera::frustumPlanes() const {
  // Side planes through the origin: x/d within +-(cx/f) etc., with d = -z.
  float tx = cx_ / focal_, ty = cy_ / focal_;
  return {Vec4f(1, 0, -tx, 0),      // left:   x >= -tx d  (d = -z)
          Vec4f(-1, 0, -tx, 0),     // right:  x <= tx d
          Vec4f(0, 1, -ty, 0),      // bottom
          Vec4f(0, -1, -ty, 0),     // top
          Vec4f(0, 0, -1, -near_),  // near:   d >= near
          Vec4f(0, 0, 1, far_)};    // far:    d <= far
}

Camera Camera::withViewport(int width, int height) const {
  return lookAt(eye_, target_, up_, fovY_, width, height, near_, far_);
}

Camera Camera::withNearFar(float nearDepth, float farDepth) const {
  return lookAt(eye_, target_, up_, fovY_, width_, height_, nearDepth, farDepth);
}

}  // namespace linesurf
