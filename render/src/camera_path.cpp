#include "simreel/render/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace simreel::render {

namespace {

/// Tangent (per second) at key i: the mean of the slopes of the two neighbouring segments
/// (a Catmull-Rom tangent that respects uneven key spacing); zero at the ends, so the camera
/// eases in and out of the first and last key.
template <class Get>
auto tangent(const std::vector<CameraKey>& keys, std::size_t i, Get get) {
  using T = decltype(get(keys[0]));
  if (i == 0 || i + 1 == keys.size()) return T(get(keys[i]) * 0.f);
  const float before = float(keys[i].time - keys[i - 1].time);
  const float after = float(keys[i + 1].time - keys[i].time);
  return T(0.5f * ((get(keys[i]) - get(keys[i - 1])) / before + (get(keys[i + 1]) - get(keys[i])) / after));
}

}  // namespace

Camera camera_at(const CameraMotion& motion, double t) {
  Camera c = motion.base;
  const auto& keys = motion.keys;
  if (!keys.empty()) {
    for (std::size_t i = 1; i < keys.size(); ++i) {
      if (!(keys[i].time > keys[i - 1].time)) {
        throw std::invalid_argument("camera path key " + std::to_string(i) +
                                    ": times must strictly increase");
      }
    }
    if (t <= keys.front().time || keys.size() == 1) {
      c.position = keys.front().position;
      c.target = keys.front().target;
      c.fov_deg = keys.front().fov_deg;
    } else if (t >= keys.back().time) {
      c.position = keys.back().position;
      c.target = keys.back().target;
      c.fov_deg = keys.back().fov_deg;
    } else {
      const auto next = std::upper_bound(keys.begin(), keys.end(), t,
                                         [](double time, const CameraKey& k) { return time < k.time; });
      const std::size_t i = std::size_t(next - keys.begin()) - 1;
      const CameraKey& a = keys[i];
      const CameraKey& b = keys[i + 1];
      const float h = float(b.time - a.time);
      const float s = float((t - a.time) / (b.time - a.time));
      // Cubic Hermite basis.
      const float s2 = s * s, s3 = s2 * s;
      const float h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
      // The explicit return type evaluates Eigen expressions before their temporaries die.
      auto hermite = [&](auto get) -> decltype(get(a)) {
        return h00 * get(a) + h10 * h * tangent(keys, i, get) + h01 * get(b) + h11 * h * tangent(keys, i + 1, get);
      };
      c.position = hermite([](const CameraKey& k) { return Vec3f(k.position); });
      c.target = hermite([](const CameraKey& k) { return Vec3f(k.target); });
      c.fov_deg = hermite([](const CameraKey& k) { return k.fov_deg; });
    }
  } else if (motion.orbit) {
    const CameraOrbit& o = *motion.orbit;
    if (!(o.radius > 0.f) || !(o.period_s > 0.f)) {
      throw std::invalid_argument("camera orbit needs radius > 0 and period_s > 0");
    }
    const double turns = t / double(o.period_s);
    const double a = double(o.start_deg) * std::numbers::pi / 180.0 +
                     2.0 * std::numbers::pi * (turns - std::floor(turns));
    c.position = o.center + Vec3f(o.radius * float(std::cos(a)), o.radius * float(std::sin(a)), o.height);
    c.target = o.center;
  }
  if ((c.target - c.position).squaredNorm() <= 0.f) {
    throw std::invalid_argument("camera at t = " + std::to_string(t) + " s has its target on the eye");
  }
  return c;
}

}  // namespace simreel::render
