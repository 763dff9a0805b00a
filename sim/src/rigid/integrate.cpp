// Semi-implicit Euler for rigid bodies with angular momentum as state (see integrate.hpp).
#include "rigid/integrate.hpp"

#include <Eigen/Cholesky>

namespace simreel::sim::detail {
namespace {

/// Fixed-point rounds of the midpoint ω: each gains a factor ~ h |ω| (κ - 1) of accuracy.
constexpr int kMidpointIterations = 3;

/// q turned by the angle |w| h about the world axis w (the exponential map of App. C's
/// dq/dt = ½ (0, ω) ⊗ q for constant ω: exact, and unit without renormalising drift).
Quat rotated(const Quat& q, const Vec3& w, double h) {
  const double speed = w.norm();
  if (!(speed > 0.0)) return q;
  return (Quat(Eigen::AngleAxisd(speed * h, w / speed)) * q).normalized();
}

}  // namespace

void integrate_velocities(RigidBodies& bodies, double h) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies.is_dynamic(i)) continue;
    const double im = bodies.inv_mass[i];
    bodies.linear_velocity[i] =
        (bodies.linear_velocity[i] + h * im * bodies.force[i]) / (1.0 + h * bodies.linear_drag[i] * im);
    Vec3 L = bodies.angular_momentum[i] + h * bodies.torque[i];
    const double kw = bodies.angular_drag[i];
    if (kw > 0.0) {
      // Backward Euler on dL/dt = -k_ω I_w⁻¹ L: (E + h k_ω I_w⁻¹) L' = L, an SPD 3x3 system.
      const Mat3 A = Mat3::Identity() + (h * kw) * bodies.inv_inertia_world[i];
      L = A.ldlt().solve(L);
    }
    bodies.angular_momentum[i] = L;
    bodies.angular_velocity[i] = bodies.inv_inertia_world[i] * L;
  }
}

void integrate_positions(RigidBodies& bodies, double h, Motion motion) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies.is_dynamic(i)) continue;
    Vec3 v = bodies.bias_velocity[i], w = bodies.bias_angular_velocity[i];
    if (motion == Motion::velocity) {
      v = bodies.linear_velocity[i];
      w = bodies.angular_velocity[i];
    } else if (motion == Motion::both) {
      v += bodies.linear_velocity[i];
      w += bodies.angular_velocity[i];
    }
    bodies.position[i] += h * v;
    Quat& q = bodies.orientation[i];
    if (motion != Motion::bias) {
      // The real rotation turns by the ω of the half-step orientation, ω(q_½) = R_½ I_b⁻¹ R_½ᵀ L
      // (implicit midpoint with L held, by fixed-point iteration): symmetric, so the kinetic
      // energy of a torque-free body stays bounded instead of drifting. The explicit ω(q_n)
      // pumps energy into the rotation until a thin body spins about its long axis at 100
      // times its energy (test_rigid_body.cpp's plank).
      const Vec3 bias = w - bodies.angular_velocity[i];
      const Vec3& L = bodies.angular_momentum[i];
      Vec3 omega = bodies.angular_velocity[i];
      for (int k = 0; k < kMidpointIterations; ++k) {
        const Mat3 R = rotated(q, omega, 0.5 * h).toRotationMatrix();
        omega = R * (bodies.inv_inertia_body[i] * (R.transpose() * L));
      }
      w = omega + bias;
    }
    q = rotated(q, w, h);
    if (motion != Motion::velocity) {
      bodies.bias_velocity[i].setZero();
      bodies.bias_angular_velocity[i].setZero();
    }
    update_derived(bodies, i);
  }
}

void step_free(RigidBodies& bodies, double h) {
  integrate_velocities(bodies, h);
  integrate_positions(bodies, h);
  clear_forces(bodies);
}

void sync_angular_momentum(RigidBodies& bodies, std::size_t i) {
  if (!bodies.is_dynamic(i)) return;
  bodies.angular_momentum[i] = world_inertia(bodies, i) * bodies.angular_velocity[i];
}

}  // namespace simreel::sim::detail
