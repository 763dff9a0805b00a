// Rigid-body state (SoA), force–torque pairs, springs (see body_state.hpp).
#include "rigid/body_state.hpp"

#include <cassert>

#include <Eigen/Cholesky>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace simreel::sim::detail {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("add_body: " + what);
}

}  // namespace

void RigidBodies::reserve(std::size_t n) {
  position.reserve(n);
  orientation.reserve(n);
  linear_velocity.reserve(n);
  angular_momentum.reserve(n);
  angular_velocity.reserve(n);
  mass.reserve(n);
  inv_mass.reserve(n);
  inertia_body.reserve(n);
  inv_inertia_body.reserve(n);
  inv_inertia_world.reserve(n);
  force.reserve(n);
  torque.reserve(n);
  linear_drag.reserve(n);
  angular_drag.reserve(n);
  bias_velocity.reserve(n);
  bias_angular_velocity.reserve(n);
  asleep.reserve(n);
}

namespace {
template <class T>
void swap_pop(std::vector<T>& a, std::size_t i) {
  a[i] = a.back();
  a.pop_back();
}
}  // namespace

void swap_remove(RigidBodies& b, std::size_t i) {
  assert(i < b.size());
  swap_pop(b.position, i);
  swap_pop(b.orientation, i);
  swap_pop(b.linear_velocity, i);
  swap_pop(b.angular_momentum, i);
  swap_pop(b.angular_velocity, i);
  swap_pop(b.mass, i);
  swap_pop(b.inv_mass, i);
  swap_pop(b.inertia_body, i);
  swap_pop(b.inv_inertia_body, i);
  swap_pop(b.inv_inertia_world, i);
  swap_pop(b.force, i);
  swap_pop(b.torque, i);
  swap_pop(b.linear_drag, i);
  swap_pop(b.angular_drag, i);
  swap_pop(b.bias_velocity, i);
  swap_pop(b.bias_angular_velocity, i);
  swap_pop(b.asleep, i);
}

std::size_t add_body(RigidBodies& bodies, const RigidBodyDef& def) {
  if (!(std::isfinite(def.mass) && def.mass >= 0.0)) {
    std::ostringstream m;
    m << "mass must be >= 0 and finite (0: static), got " << def.mass;
    fail(m.str());
  }
  if (!def.position.allFinite() || !def.linear_velocity.allFinite() ||
      !def.angular_velocity.allFinite())
    fail("position and velocities must be finite");
  const double qn = def.orientation.norm();
  if (!(std::isfinite(qn) && qn > 0.0)) fail("orientation must be a non-zero finite quaternion");
  if (!(def.linear_drag >= 0.0 && def.angular_drag >= 0.0))
    fail("drag coefficients must be >= 0");
  const bool dynamic = def.mass > 0.0;
  Mat3 inv_inertia = Mat3::Zero();
  if (dynamic) {
    const Mat3& I = def.inertia;
    const double scale = I.cwiseAbs().maxCoeff();
    if (!I.allFinite() || !(scale > 0.0) || (I - I.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale)
      fail("inertia of a dynamic body must be finite and symmetric");
    const Eigen::LLT<Mat3> llt(I);
    if (llt.info() != Eigen::Success) fail("inertia of a dynamic body must be positive definite");
    inv_inertia = llt.solve(Mat3::Identity());
    inv_inertia = 0.5 * (inv_inertia + inv_inertia.transpose()).eval();
  }
  const std::size_t i = bodies.size();
  const Quat q = def.orientation.normalized();
  const Mat3 R = q.toRotationMatrix();
  bodies.position.push_back(def.position);
  bodies.orientation.push_back(q);
  bodies.linear_velocity.push_back(dynamic ? def.linear_velocity : Vec3::Zero());
  // L = I_w ω, so that ω comes back unchanged from ω = I_w⁻¹ L.
  bodies.angular_momentum.push_back(dynamic ? Vec3(R * def.inertia * R.transpose() *
                                                   def.angular_velocity)
                                            : Vec3::Zero());
  bodies.angular_velocity.push_back(dynamic ? def.angular_velocity : Vec3::Zero());
  bodies.mass.push_back(def.mass);
  bodies.inv_mass.push_back(dynamic ? 1.0 / def.mass : 0.0);
  bodies.inertia_body.push_back(dynamic ? def.inertia : Mat3::Zero());
  bodies.inv_inertia_body.push_back(inv_inertia);
  bodies.inv_inertia_world.push_back(R * inv_inertia * R.transpose());
  bodies.force.push_back(Vec3::Zero());
  bodies.torque.push_back(Vec3::Zero());
  bodies.linear_drag.push_back(def.linear_drag);
  bodies.angular_drag.push_back(def.angular_drag);
  bodies.bias_velocity.push_back(Vec3::Zero());
  bodies.bias_angular_velocity.push_back(Vec3::Zero());
  bodies.asleep.push_back(0);
  return i;
}

void sleep(RigidBodies& bodies, std::size_t i) {
  assert(bodies.is_dynamic(i));
  bodies.asleep[i] = 1;
  bodies.linear_velocity[i].setZero();
  bodies.angular_momentum[i].setZero();
  bodies.angular_velocity[i].setZero();
  bodies.force[i].setZero();
  bodies.torque[i].setZero();
  bodies.bias_velocity[i].setZero();
  bodies.bias_angular_velocity[i].setZero();
  bodies.inv_mass[i] = 0.0;
  bodies.inv_inertia_world[i].setZero();
}

void wake(RigidBodies& bodies, std::size_t i) {
  if (!bodies.asleep[i]) return;
  bodies.asleep[i] = 0;
  bodies.inv_mass[i] = 1.0 / bodies.mass[i];
  update_derived(bodies, i);
}

void update_derived(RigidBodies& bodies, std::size_t i) {
  const Mat3 R = bodies.orientation[i].toRotationMatrix();
  bodies.inv_inertia_world[i] = R * bodies.inv_inertia_body[i] * R.transpose();
  bodies.angular_velocity[i] = bodies.inv_inertia_world[i] * bodies.angular_momentum[i];
}

Mat3 world_inertia(const RigidBodies& bodies, std::size_t i) {
  const Mat3 R = bodies.orientation[i].toRotationMatrix();
  return R * bodies.inertia_body[i] * R.transpose();
}

Vec3 point_velocity(const RigidBodies& bodies, std::size_t i, const Vec3& p) {
  return bodies.linear_velocity[i] + bodies.angular_velocity[i].cross(p - bodies.position[i]);
}

void apply_force(RigidBodies& bodies, std::size_t i, const Vec3& F) { bodies.force[i] += F; }

void apply_torque(RigidBodies& bodies, std::size_t i, const Vec3& tau) {
  bodies.torque[i] += tau;
}

void apply_force_at(RigidBodies& bodies, std::size_t i, const Vec3& F, const Vec3& p) {
  bodies.force[i] += F;
  bodies.torque[i] += (p - bodies.position[i]).cross(F);
}

void apply_gravity(RigidBodies& bodies, const Vec3& g) {
  for (std::size_t i = 0; i < bodies.size(); ++i) bodies.force[i] += bodies.mass[i] * g;
}

void apply_spring(RigidBodies& bodies, std::size_t a, const Vec3& pa_body, std::size_t b,
                  const Vec3& pb_body, double rest, double ks, double kd) {
  const Vec3 pa = bodies.orientation[a] * pa_body + bodies.position[a];
  const Vec3 pb = bodies.orientation[b] * pb_body + bodies.position[b];
  const Vec3 d = pb - pa;
  const double len = d.norm();
  if (!(len > 0.0)) return;  // direction undefined; a zero-length spring pulls nowhere
  const Vec3 u = d / len;
  const double closing = (point_velocity(bodies, b, pb) - point_velocity(bodies, a, pa)).dot(u);
  const Vec3 F = (ks * (len - rest) + kd * closing) * u;  // on a, towards b when stretched
  apply_force_at(bodies, a, F, pa);
  apply_force_at(bodies, b, -F, pb);
}

void apply_impulse_at(RigidBodies& bodies, std::size_t i, const Vec3& J, const Vec3& p) {
  if (!bodies.is_dynamic(i)) return;
  bodies.linear_velocity[i] += bodies.inv_mass[i] * J;
  bodies.angular_momentum[i] += (p - bodies.position[i]).cross(J);
  bodies.angular_velocity[i] = bodies.inv_inertia_world[i] * bodies.angular_momentum[i];
}

void clear_forces(RigidBodies& bodies) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    bodies.force[i].setZero();
    bodies.torque[i].setZero();
  }
}

double kinetic_energy(const RigidBodies& bodies, std::size_t i) {
  return 0.5 * bodies.mass[i] * bodies.linear_velocity[i].squaredNorm() +
         0.5 * bodies.angular_velocity[i].dot(bodies.angular_momentum[i]);
}

}  // namespace simreel::sim::detail
