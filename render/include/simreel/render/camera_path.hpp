#pragma once
/// @file camera_path.hpp
/// A camera that moves with time: keyframes interpolated smoothly, or an orbit around a point.
/// The program evaluates it once per frame and hands the result to Renderer::set_camera.

#include <optional>
#include <vector>

#include "simreel/render/renderer.hpp"

namespace simreel::render {

/// One camera keyframe.
struct CameraKey {
  double time = 0.0;                 ///< (s) scene time of the key
  Vec3f position{6.f, -6.f, 3.f};    ///< (m) eye, world frame
  Vec3f target{0.f, 0.f, 0.5f};      ///< (m) point looked at
  float fov_deg = 40.f;              ///< vertical field of view (degrees)
};

/// Circles `center` at `radius` and `height` above it, counter-clockwise seen from above
/// (+z), looking at `center`: eye = center + (r cos a, r sin a, height),
/// a = start_deg + 360 t / period_s.
struct CameraOrbit {
  Vec3f center{0.f, 0.f, 0.5f};  ///< (m) point circled and looked at
  float radius = 6.f;            ///< (m) horizontal distance from center, > 0
  float height = 2.f;            ///< (m) eye height above center
  float period_s = 10.f;         ///< (s) time for one turn; > 0
  float start_deg = -90.f;       ///< (degrees) angle at t = 0 from +x towards +y (-90: on -y)
};

/// How the camera moves. With neither keys nor an orbit, `base` stays where it is.
struct CameraMotion {
  Camera base;                     ///< up, clip distances, and the pose when nothing moves it
  std::vector<CameraKey> keys;     ///< strictly increasing times; may be empty
  std::optional<CameraOrbit> orbit;  ///< used when there are no keys
};

/// The camera at scene time t (s). Keys: position, target and fov follow a cubic Hermite
/// spline through every key (Catmull-Rom tangents from the neighbouring keys, scaled for
/// uneven spacing; zero slope at the first and last key), so the path passes exactly
/// through each key at its time, with a continuous velocity; before the first key and after
/// the last the camera holds still. @throws std::invalid_argument if key times do not
/// strictly increase, an orbit has radius <= 0 or period_s <= 0, or the result has the
/// target on the eye.
Camera camera_at(const CameraMotion& motion, double t);

}  // namespace simreel::render
