// Semi-implicit Euler for rigid bodies with angular momentum as state (see integrate.hpp).
#include "rigid/integrate.hpp"

#include <Eigen/Cholesky>

namespace simreel::sim::detail {

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
    // dq/dt = ½ (0, ω) ⊗ q with ω in the world frame (Coutinho App. C).
    const Quat dq = Quat(0.0, w.x(), w.y(), w.z()) * q;
    q.coeffs() += (0.5 * h) * dq.coeffs();
    q.normalize();
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
