// Stage "bodies" (stages.hpp; Coutinho Ch. 4): dynamic bodies over one step h —
//   kinematic bodies' rigid entries take their path velocity (§3.7: it enters the contacts),
//   broad and narrow phase with warm-started manifolds (body_contacts.cpp, §4.4–4.7),
//   gravity, the impulses of particles and cloth logged this step and the force fields
//   (body_coupling.cpp, §3.7), then prepare -> integrate velocities (forces, drag §4.3) -> sequential impulses
//   (§4.8) -> integrate positions (§4.2, App. C) as rigid/contact_solver.hpp's step_with_contacts,
//   the impulses kept in the manifolds for the next step's warm start,
//   each dynamic body's frame and shapes placed from its centre of mass.
//   then rest times and islands: islands at rest fall asleep (sleep.cpp, body_dynamics.hpp).
// Nothing runs without a dynamic body, so scenes before Ch. 4 are bit-identical. Serial, in the
// bodies' dense order: deterministic at any thread count.
#include "core/stages.hpp"
#include "core/union_find.hpp"
#include <sstream>

#include "rigid/integrate.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim::detail {
namespace {

/// d.in_contact[i] = 1 for every body of an articulation (bodies joined by joints) of which
/// some body touches something this step: those take the joint projection as a position
/// correction only (joint_solver.hpp project_positions).
void mark_articulations_in_contact(BodyDynamics& d) {
  const std::uint32_t n = std::uint32_t(d.rigid.size());
  d.in_contact.assign(n, 0);
  d.parent.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) d.parent[i] = i;
  for (const JointBodies& j : d.joint_bodies)
    if (j.a != kStaticBody && j.b != kStaticBody) {
      uf_unite(d.parent, j.a, j.b);
    }
  for (const BodyManifold& m : d.manifolds) {
    if (m.manifold.count == 0 || m.first_point == kCarriedManifold) continue;
    if (m.rigid_a != kStaticBody) d.in_contact[uf_find(d.parent, m.rigid_a)] = 1;
    if (m.rigid_b != kStaticBody) d.in_contact[uf_find(d.parent, m.rigid_b)] = 1;
  }
  for (std::uint32_t i = 0; i < n; ++i) d.in_contact[i] = d.in_contact[uf_find(d.parent, i)];
}

/// L ← I_w ω for every dynamic body (after a sweep changed ω directly).
void sync_all(RigidBodies& r) {
  for (std::size_t i = 0; i < r.size(); ++i)
    if (r.is_dynamic(i)) sync_angular_momentum(r, i);
}

/// The soft step (WorldDef::body_substeps >= 2; rigid/contact_solver.hpp): the contacts found
/// once for the step h, then n substeps of h/n of integrate velocities -> warm start -> biased
/// sweep(s) -> integrate positions -> relax sweep(s), joints solved exactly after every contact
/// sweep (§5.4, as in the one-step path); restitution once; the joint projection (drift, §5.4)
/// once at the end of the step, its displacement turned into velocity for articulations that
/// touch nothing (RATTLE).
void soft_step(WorldState& w, double h, int n) {
  BodyDynamics& d = w.dyn;
  RigidBodies& r = d.rigid;
  JointSolver& js = d.joint_solver;
  ContactSolver& cs = d.solver;
  const double hs = h / n;
  const ContactSolverSettings& set = cs.settings();
  // Contact rows and joint rows with the same (stiffened) inertias, so that their alternation
  // solves one system.
  js.stiffen_inertia(r, d.joint_models, d.joint_bodies, d.joint_force_n, hs);
  cs.prepare_soft(r, d.points, hs);
  js.restore_inertia(r);
  bool joints = false;
  for (int s = 0; s < n; ++s) {
    integrate_velocities(r, hs);
    js.stiffen_inertia(r, d.joint_models, d.joint_bodies, d.joint_force_n, hs);
    js.prepare(r, d.joint_models, d.joint_bodies, hs);
    js.restore_inertia(r);
    joints = !js.empty();
    cs.warm_start_soft(r, d.points);
    if (joints) js.solve_equality(r);
    for (int it = 0; it < set.substep_iterations; ++it) {
      cs.solve_soft(r, d.points, true);
      if (joints) {
        js.iterate_rows(r);
        js.solve_equality(r);
      }
    }
    sync_all(r);
    integrate_positions(r, hs, Motion::velocity);
    cs.track_separations(r);
    js.stiffen_inertia(r, d.joint_models, d.joint_bodies, d.joint_force_n, hs);
    cs.refresh_soft(r);  // the lever arms and the world inertia turned with the bodies
    js.restore_inertia(r);
    for (int it = 0; it < set.relax_iterations; ++it) {
      cs.solve_soft(r, d.points, false);
      if (joints) {
        js.iterate_rows(r);
        js.solve_equality(r);
      }
    }
    sync_all(r);
  }
  cs.restitution_soft(r, d.points);
  sync_all(r);
  if (joints) {
    js.finish(r);
    finish_joints(w, hs);  // the last substep's impulses over its length: the joint forces
    mark_articulations_in_contact(d);
    js.project_positions(r, d.joint_models, d.joint_bodies, h, d.in_contact);
  }
}

}  // namespace

void stage_bodies(WorldState& w, double t0, double t1) {
  BodyDynamics& d = w.dyn;
  if (d.dynamic_count == 0) return;
  const double h = t1 - t0;
  RigidBodies& r = d.rigid;
  std::vector<Body>& bodies = w.bodies.dense();
  for (const Body& b : bodies)
    if (b.kinematic()) {
      // Pose and velocities at t1 (stage "kinematic poses"); the rigid entry's position is the
      // body origin, the point the path velocity is of.
      r.position[b.rigid] = b.pose.translation;
      r.linear_velocity[b.rigid] = b.velocity;
      r.angular_velocity[b.rigid] = b.angular_velocity;
    }
  // This step's joints by rigid entry (removals move rigid entries), before the contacts: joined
  // bodies skip each other's contacts and wake each other.
  gather_joints(w);
  // Bodies that particles or cloth pushed, or that a force field acts on, wake before their
  // contacts are found.
  wake_coupled(w, t0, t1);
  begin_continuous(w, h);  // start poses; fast bodies' contacts take a speculative margin
  find_body_contacts(w);
  // A sleeping island touched by something moving wakes; its own contacts were skipped, so
  // they are found again with it awake.
  if (wake_touched(w)) find_body_contacts(w);
  for (const Body& b : bodies)
    if (b.dynamic() && r.is_dynamic(b.rigid)) apply_force(r, b.rigid, r.mass[b.rigid] * b.gravity);
  apply_body_springs(w);  // §4.3.3
  // Particles' and cloth's impulses of this step, force fields (§3.7; body_coupling.cpp).
  apply_coupling(w, t0, t1);
  JointSolver& js = d.joint_solver;
  if (w.def.body_substeps > 1) {
    soft_step(w, h, w.def.body_substeps);
  } else {
  // A light link under a large joint force gets the geometric stiffness of that force added to
  // its inertia for the solve (joint_solver.hpp), the contact rows as well as the joint rows.
  js.stiffen_inertia(r, d.joint_models, d.joint_bodies, d.joint_force_n, h);
  d.solver.prepare(r, d.points, h);
  js.prepare(r, d.joint_models, d.joint_bodies, h);
  js.restore_inertia(r);
  integrate_velocities(r, h);
  if (js.empty()) {
    d.solver.solve(r, d.points);
  } else {
    // Contacts and joints together (§5.4; joint_solver.hpp): block Gauss–Seidel whose every
    // sweep ends with the exact joint solve, so contact impulses reach the whole articulation.
    d.solver.warm_start(r, d.points);
    js.solve_equality(r);
    for (int it = 0; it < d.solver.settings().velocity_iterations; ++it) {
      d.solver.iterate_velocities(r, d.points);
      js.iterate_rows(r);
      js.solve_equality(r);
    }
    d.solver.solve_positions(r);
    d.solver.finish(r);
    js.finish(r);
    finish_joints(w, h);
  }
  if (js.empty()) {
    integrate_positions(r, h);
  } else {
    // Drift (§5.4): the anchors projected back together and limits back inside after the real
    // motion, the projection's displacement becoming velocity (joint_solver.hpp); then the
    // contacts' split-impulse displacement, projected again without touching the velocities — a
    // joint must not turn a contact's position correction into motion (links pushed apart by a
    // contact and pulled back by their joint would otherwise gain speed every step).
    integrate_positions(r, h, Motion::velocity);
    mark_articulations_in_contact(d);
    js.project_positions(r, d.joint_models, d.joint_bodies, h, d.in_contact);
    integrate_positions(r, h, Motion::bias);
    js.project_positions(r, d.joint_models, d.joint_bodies, h, {});
  }
  }
  continuous_collisions(w, h);  // fast bodies back to their time of impact (body_ccd.cpp)
  clear_forces(r);
  // The solver's impulses go back into the manifolds: next step's warm start (tangent impulses
  // as world vectors, persistent_manifold.hpp).
  for (BodyManifold& m : d.manifolds) {
    if (m.first_point == kCarriedManifold) continue;
    for (int k = 0; k < m.manifold.count; ++k) {
      const ContactPoint& c = d.points[m.first_point + std::uint32_t(k)];
      Vec3 t1v, t2v;
      tangent_basis(c.normal, t1v, t2v);
      m.manifold.points[k].normal_impulse = c.normal_impulse;
      m.manifold.points[k].tangent_impulse = c.tangent_impulse[0] * t1v + c.tangent_impulse[1] * t2v;
    }
  }
  update_sleep(w, h);
  std::swap(d.previous, d.manifolds);
  for (Body& b : bodies) {
    if (!b.dynamic()) continue;
    const std::uint32_t i = b.rigid;
    // Stop before the shapes and the moved list carry NaNs to the collisions and the renderer.
    // A speed above that of light (or a spin whose rim would pass it) is an explosion of the
    // solve, not motion: it stops the run too, long before it overflows.
    if (!(r.position[i].allFinite() && r.orientation[i].coeffs().allFinite() &&
          r.linear_velocity[i].norm() < kDivergedSpeed && r.angular_velocity[i].norm() < kDivergedSpeed)) {
      std::ostringstream m;
      m.precision(9);
      m << "body '" << b.name << "': non-finite position or velocity (faster than light) at internal step "
        << w.steps + 1 << ", t = " << t1 << " s";
      // Motion the step does not resolve (a link 1000 times lighter than the load on its chain,
      // a whip crack) is what blows up here: say what resolves it.
      m << "; motion faster than the step resolves: a smaller simulation.max_step (now " << h
        << " s) or simulation.body_substeps (now " << w.def.body_substeps << ") may resolve it";
      throw NonFiniteState(m.str());
    }
    const Quat& q = r.orientation[i];
    const Vec3 arm = q * b.local_com;
    b.pose.rotation = q;
    b.pose.translation = r.position[i] - arm;
    b.angular_velocity = r.angular_velocity[i];
    b.velocity = r.linear_velocity[i] - b.angular_velocity.cross(arm);  // of the body origin
    for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k)
      w.shapes[k].follow(b.pose, b.velocity, b.angular_velocity);
  }
}

}  // namespace simreel::sim::detail
