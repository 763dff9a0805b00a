#pragma once
// Private: view, projection and model matrices (column-major, OpenGL clip conventions).

#include <cmath>

#include <Eigen/Core>

namespace simreel::render::detail {

using Mat4f = Eigen::Matrix4f;

/// A unit vector perpendicular to the unit vector `n`.
inline Eigen::Vector3f any_perpendicular(const Eigen::Vector3f& n) {
  const Eigen::Vector3f ref = std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  return (ref - n * n.dot(ref)).normalized();
}

/// World -> view (right-handed, looking down -z).
inline Mat4f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                     const Eigen::Vector3f& up) {
  const Eigen::Vector3f f = (target - eye).normalized();
  Eigen::Vector3f s = f.cross(up);
  if (s.squaredNorm() < 1e-12f) s = f.cross(any_perpendicular(f));  // looking along `up`
  s.normalize();
  const Eigen::Vector3f u = s.cross(f);
  Mat4f m = Mat4f::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

/// View -> clip; fovy in radians, distances in metres.
inline Mat4f perspective(float fovy_rad, float aspect, float near_m, float far_m) {
  const float t = 1.f / std::tan(0.5f * fovy_rad);
  Mat4f m = Mat4f::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (far_m + near_m) / (near_m - far_m);
  m(2, 3) = 2.f * far_m * near_m / (near_m - far_m);
  m(3, 2) = -1.f;
  return m;
}

inline Mat4f ortho(float half_w, float half_h, float near_m, float far_m) {
  Mat4f m = Mat4f::Identity();
  m(0, 0) = 1.f / half_w;
  m(1, 1) = 1.f / half_h;
  m(2, 2) = -2.f / (far_m - near_m);
  m(2, 3) = -(far_m + near_m) / (far_m - near_m);
  return m;
}

/// x -> linear * x + translation.
inline Mat4f affine(const Eigen::Matrix3f& linear, const Eigen::Vector3f& translation) {
  Mat4f m = Mat4f::Identity();
  m.block<3, 3>(0, 0) = linear;
  m.block<3, 1>(0, 3) = translation;
  return m;
}

}  // namespace simreel::render::detail
