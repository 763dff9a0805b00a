// Keyframed rigid paths: sampling, velocities and validation.
#include "simreel/sim/keyframes.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/path_math.hpp"
#include "core/validate.hpp"

namespace simreel::sim {
namespace {

/// Maps t into the path's time range: clamped, or wrapped with period (last - first) when looping.
double local_time(const KeyframePath& p, double t) {
  const double t_first = p.keys.front().time;
  const double t_last = p.keys.back().time;
  if (p.loop && t_last > t_first) {
    const double period = t_last - t_first;
    double u = std::fmod(t - t_first, period);
    if (u < 0.0) u += period;
    return t_first + u;
  }
  return std::clamp(t, t_first, t_last);
}

/// Neighbour key i (may be -1 or n) as (time, position). When looping, the first and last keys
/// are the same instant of the cycle, so neighbours wrap past them shifted by one period;
/// otherwise the end keys are repeated, which makes the end tangents one-sided.
void neighbour(const KeyframePath& p, long i, double& time, Vec3& pos) {
  const long n = long(p.keys.size());
  const double period = p.keys.back().time - p.keys.front().time;
  if (i < 0) {
    if (p.loop && n >= 3) {
      time = p.keys[std::size_t(n - 2)].time - period;
      pos = p.keys[std::size_t(n - 2)].position;
    } else {
      time = p.keys[0].time;
      pos = p.keys[0].position;
    }
  } else if (i >= n) {
    if (p.loop && n >= 3) {
      time = p.keys[1].time + period;
      pos = p.keys[1].position;
    } else {
      time = p.keys[std::size_t(n - 1)].time;
      pos = p.keys[std::size_t(n - 1)].position;
    }
  } else {
    time = p.keys[std::size_t(i)].time;
    pos = p.keys[std::size_t(i)].position;
  }
}

/// Finite-difference tangent (m/s) at key i over its neighbours (Catmull–Rom with time-scaled
/// tangents, so unevenly spaced keys do not overshoot).
Vec3 tangent(const KeyframePath& p, long i) {
  double t0, t1;
  Vec3 p0, p1;
  neighbour(p, i - 1, t0, p0);
  neighbour(p, i + 1, t1, p1);
  return t1 > t0 ? Vec3((p1 - p0) / (t1 - t0)) : Vec3::Zero();
}

}  // namespace

Transform KeyframePath::sample(double t) const {
  if (keys.empty()) throw std::logic_error("KeyframePath::sample: the path has no keys");
  Transform out;
  if (keys.size() == 1 || !std::isfinite(t)) {
    const Keyframe& k = keys.size() == 1 || !(t > keys.front().time) ? keys.front() : keys.back();
    out.translation = k.position;
    out.rotation = k.rotation.normalized();
    return out;
  }
  const double tl = local_time(*this, t);
  // Segment i: keys[i].time <= tl < keys[i+1].time (the last segment also takes tl == last).
  auto it = std::upper_bound(keys.begin(), keys.end(), tl,
                             [](double v, const Keyframe& k) { return v < k.time; });
  std::size_t i = std::size_t(std::max<std::ptrdiff_t>(it - keys.begin() - 1, 0));
  i = std::min(i, keys.size() - 2);
  const Keyframe& a = keys[i];
  const Keyframe& b = keys[i + 1];
  const double dt = b.time - a.time;
  const double u = std::clamp((tl - a.time) / dt, 0.0, 1.0);

  if (smooth) {
    // Cubic Hermite basis with Catmull–Rom tangents.
    const double u2 = u * u, u3 = u2 * u;
    const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u;
    const double h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
    out.translation = h00 * a.position + h10 * dt * tangent(*this, long(i)) + h01 * b.position +
                      h11 * dt * tangent(*this, long(i) + 1);
  } else {
    out.translation = (1.0 - u) * a.position + u * b.position;
  }
  out.rotation = a.rotation.normalized().slerp(u, b.rotation.normalized());
  return out;
}

Vec3 KeyframePath::velocity(double t, double h) const {
  return (sample(t + h).translation - sample(t - h).translation) / (2.0 * h);
}

namespace detail {

Vec3 angular_velocity(const KeyframePath& path, double t, double h) {
  const Quat q0 = path.sample(t - h).rotation;
  const Quat q1 = path.sample(t + h).rotation;
  Eigen::AngleAxisd aa(q1 * q0.conjugate());
  double angle = aa.angle();
  if (angle > 3.141592653589793) angle -= 2.0 * 3.141592653589793;  // shortest way round
  return aa.axis() * (angle / (2.0 * h));
}

void validate(const KeyframePath& path, const std::string& what) {
  for (std::size_t i = 0; i < path.keys.size(); ++i) {
    const Keyframe& k = path.keys[i];
    std::ostringstream where;
    where << what << ".keys[" << i << "]";
    if (!std::isfinite(k.time) || !k.position.allFinite() || !k.rotation.coeffs().allFinite())
      throw std::invalid_argument(where.str() + ": time, position and rotation must be finite");
    require_in(k.time, ranges::kKeyframeTime, where.str() + ".time");
    if (!(k.rotation.norm() > 1e-12))
      throw std::invalid_argument(where.str() + ": rotation quaternion has zero length");
    if (i > 0 && !(k.time > path.keys[i - 1].time)) {
      std::ostringstream msg;
      msg << where.str() << ": key times must be strictly increasing (got " << k.time
          << " after " << path.keys[i - 1].time << ")";
      throw std::invalid_argument(msg.str());
    }
  }
}

}  // namespace detail
}  // namespace simreel::sim
