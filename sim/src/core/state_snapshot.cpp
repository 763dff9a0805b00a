// World::save_state / load_state: the complete state that carries from one advance() to the next,
// one section per subsystem (state_io.hpp), so that a world built from the same definitions and
// loaded with a saved state continues bit-identically to the world it was saved from (a
// simulation cache resumed or rendered from any frame; docs/cache.md).
//
// What is saved is what a step reads before it writes it: time and step count; per body its pose,
// velocities and last reported pose; per shape its pose and the previous step's pose (swept
// tests); the rigid state of every dynamic and kinematic body (Coutinho §4.2: x, q, v, L, ω, the
// inverse masses and inertias a sleeping body zeroes, the split-impulse velocities); last step's
// contact manifolds with their accumulated impulses (warm start, §4.8) and the sleep bookkeeping;
// per particle system every live particle's attributes, the emitter schedule, bursts, next id,
// its random generators, springs and adaptive step; the particle-particle warm starts; per cloth
// its positions, velocities and last Δv (cloth.cpp). Scratch rebuilt every step (broad-phase
// proxies, solver rows, grids, workspaces) and the model (definitions, topology, mesh trees,
// noise lattices) are not: they come from the scene.
//
// Joints (Coutinho Ch. 5): whether each broke and what it applied over the last step (its
// reading; a sleeping joint keeps the one it fell asleep with). The joint solver itself keeps
// nothing from step to step (its sequential-impulse rows start from zero; its cached sparsity
// pattern only skips an analysis that gives the same ordering).
//
// A new subsystem adds a section here, written by a save_X / load_X pair like the ones below,
// and bumps kStateFormat.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/state_io.hpp"
#include "simreel/sim/ranges.hpp"
#include "core/world_impl.hpp"

namespace simreel::sim {

namespace {

using detail::StateReader;
using detail::StateWriter;
using detail::WorldState;

constexpr std::uint64_t kMagic = 0x3154535245455253ULL;  // "SREESTS1" little-endian

// --- world: time and step count ------------------------------------------------------------

void save_clock(const WorldState& w, StateWriter& out) {
  out.begin("WRLD");
  out.value(w.time);
  out.value(w.steps);
  out.end();
}

void load_clock(WorldState& w, StateReader& in) {
  in.begin("WRLD");
  in.value(w.time);
  in.value(w.steps);
  in.end();
  detail::require_finite(w.time, "the world time");
}

// --- bodies: poses and velocities of the body frames, what was last reported ---------------

void save_bodies(const WorldState& w, StateWriter& out) {
  out.begin("BODY");
  const std::vector<detail::Body>& bodies = w.bodies.dense();
  out.value(std::uint64_t(bodies.size()));
  for (const detail::Body& b : bodies) {
    out.value(std::uint8_t(b.type));
    out.value(b.pose.translation);
    out.value(b.pose.rotation);
    out.value(b.velocity);
    out.value(b.angular_velocity);
    out.value(b.reported_translation);
    out.value(b.reported_rotation);
  }
  out.end();
}

void load_bodies(WorldState& w, StateReader& in) {
  in.begin("BODY");
  std::vector<detail::Body>& bodies = w.bodies.dense();
  in.count(bodies.size(), "bodies");
  for (detail::Body& b : bodies) {
    if (in.value<std::uint8_t>() != std::uint8_t(b.type))
      throw StateError("state: body '" + b.name + "' has another motion type");
    in.value(b.pose.translation);
    in.value(b.pose.rotation);
    in.value(b.velocity);
    in.value(b.angular_velocity);
    in.value(b.reported_translation);
    in.value(b.reported_rotation);
    const std::string of = "body '" + b.name + "' ";
    detail::require_finite(b.pose.translation, of + "position");
    detail::require_finite(b.pose.rotation, of + "orientation");
    detail::require_finite(b.velocity, of + "velocity");
    detail::require_finite(b.angular_velocity, of + "angular velocity");
    detail::require_finite(b.reported_translation, of + "reported position");
    detail::require_finite(b.reported_rotation, of + "reported orientation");
  }
  in.end();
}

// --- shapes: world poses at the end of the last step and the step before -------------------

void save_shapes(const WorldState& w, StateWriter& out) {
  out.begin("SHAP");
  out.value(std::uint64_t(w.shapes.size()));
  for (const detail::Collider& c : w.shapes) {
    out.value(std::uint8_t(c.shape));
    out.value(c.point);
    out.value(c.normal);
    out.value(c.center);
    out.value(c.rotation);
    out.value(c.R);
    out.value(c.velocity);
    out.value(c.angular_velocity);
    out.value(c.prev_center);
    out.value(c.prev_R);
    out.value(c.aabb_center);
    out.value(c.aabb_half);
  }
  out.end();
}

/// What Collider::set_pose() and follow() leave in a shape (collision/collider.cpp), checked on a
/// loaded state: finite poses and velocities below light's; a unit normal; a unit orientation
/// with R its rotation matrix; an orthonormal previous rotation; a finite bounding box of
/// non-negative size (a plane's box is not read). A corrupt pose otherwise loaded and sent the
/// bodies touching it off at the next step.
void check_shape(const detail::Collider& c, std::size_t k) {
  constexpr double kTol = 1e-6;
  const auto bad = [&](const std::string& what) {
    throw StateError("state: shape " + std::to_string(k) + ": " + what);
  };
  for (const Vec3* v : {&c.point, &c.normal, &c.center, &c.velocity, &c.angular_velocity, &c.prev_center})
    if (!v->allFinite()) bad("a position, normal or velocity is not finite");
  if (!(c.rotation.coeffs().allFinite() && c.R.allFinite() && c.prev_R.allFinite()))
    bad("a rotation is not finite");
  if (!(c.velocity.norm() < detail::kDivergedSpeed && c.angular_velocity.norm() < detail::kDivergedSpeed)) bad("moves or spins faster than light");
  if (!(std::abs(c.normal.norm() - 1.0) <= kTol)) bad("the normal is not a unit vector");
  if (!(std::abs(c.rotation.norm() - 1.0) <= kTol)) bad("the orientation is not a unit quaternion");
  if (!((c.R - c.rotation.toRotationMatrix()).cwiseAbs().maxCoeff() <= kTol))
    bad("the rotation matrix is not the orientation's");
  if (!((c.prev_R.transpose() * c.prev_R - Mat3::Identity()).cwiseAbs().maxCoeff() <= kTol))
    bad("the previous rotation matrix is not a rotation");
  if (c.shape != detail::Collider::Shape::plane &&
      !(c.aabb_center.allFinite() && c.aabb_half.allFinite() && c.aabb_half.minCoeff() >= 0.0))
    bad("the bounding box is not finite and of non-negative size");
}

void load_shapes(WorldState& w, StateReader& in) {
  in.begin("SHAP");
  in.count(w.shapes.size(), "shapes");
  std::size_t k = 0;
  for (detail::Collider& c : w.shapes) {
    if (in.value<std::uint8_t>() != std::uint8_t(c.shape)) throw StateError("state: a shape has another type");
    in.value(c.point);
    in.value(c.normal);
    in.value(c.center);
    in.value(c.rotation);
    in.value(c.R);
    in.value(c.velocity);
    in.value(c.angular_velocity);
    in.value(c.prev_center);
    in.value(c.prev_R);
    in.value(c.aabb_center);
    in.value(c.aabb_half);
    check_shape(c, k++);
    c.note_pose();  // derived from the poses just read, as set_pose() derives it
  }
  in.end();
}

// --- rigid state of dynamic and kinematic bodies (rigid/body_state.hpp) --------------------

void save_rigid(const detail::RigidBodies& r, StateWriter& out) {
  out.begin("RIGD");
  out.value(std::uint64_t(r.size()));
  out.array(r.position);
  out.array(r.orientation);
  out.array(r.linear_velocity);
  out.array(r.angular_momentum);
  out.array(r.angular_velocity);
  out.array(r.mass);
  out.array(r.inv_mass);
  out.array(r.inertia_body);
  out.array(r.inv_inertia_body);
  out.array(r.inv_inertia_world);
  out.array(r.force);
  out.array(r.torque);
  out.array(r.linear_drag);
  out.array(r.angular_drag);
  out.array(r.bias_velocity);
  out.array(r.bias_angular_velocity);
  out.array(r.asleep);
  out.end();
}

/// The relations a step keeps between the rigid arrays (rigid/body_state.cpp, Coutinho §4.2 and
/// App. C), checked on a loaded state: finite, non-negative mass and drags; a dynamic body's
/// inertia symmetric positive definite with I_b⁻¹ its inverse; awake, 1/m and I_w⁻¹ = R I_b⁻¹ Rᵀ
/// with ω = I_w⁻¹ L (update_derived() leaves them so, to rounding); asleep or static, zero inverse
/// mass and world inverse inertia; unit orientations; speeds below the one at which a step stops
/// the run as diverged (stage_bodies.cpp). A corrupt matrix or momentum otherwise loaded and
/// blew the body up at the next step ("faster than light", exit 1).
void check_rigid(const detail::RigidBodies& r) {
  constexpr double kTol = 1e-6;           // relative; the step leaves them equal to rounding
  const std::size_t n = r.size();
  const auto bad = [&](std::size_t i, const std::string& what) {
    throw StateError("state: rigid body " + std::to_string(i) + " of " + std::to_string(n) + ": " + what);
  };
  const auto close = [](const auto& a, const auto& b, double scale) {
    return (a - b).cwiseAbs().maxCoeff() <= kTol * scale + 1e-300;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double m = r.mass[i];
    if (!(std::isfinite(m) && m >= 0.0 && r.linear_drag[i] >= 0.0 && r.angular_drag[i] >= 0.0 &&
          std::isfinite(r.linear_drag[i]) && std::isfinite(r.angular_drag[i]) && r.inertia_body[i].allFinite()))
      bad(i, "mass, inertia or drag is not a finite number >= 0");
    if (!(std::abs(r.orientation[i].norm() - 1.0) <= kTol))
      bad(i, "orientation is not a unit quaternion (norm " + format_number(r.orientation[i].norm()) + ")");
    for (const Vec3* v : {&r.linear_velocity[i], &r.angular_velocity[i], &r.bias_velocity[i],
                          &r.bias_angular_velocity[i]})
      if (!(v->norm() < detail::kDivergedSpeed)) bad(i, "moves or spins faster than light (a speed of " + format_number(v->norm()) + ")");
    const Mat3& I = r.inertia_body[i];
    const Mat3& Ib_inv = r.inv_inertia_body[i];
    const Mat3& Iw_inv = r.inv_inertia_world[i];
    if (m == 0.0) {  // static or kinematic: infinite mass
      if (r.inv_mass[i] != 0.0 || !Ib_inv.isZero(0.0) || !Iw_inv.isZero(0.0))
        bad(i, "a static or kinematic body has a non-zero inverse mass or inertia");
      continue;
    }
    const double scale = I.cwiseAbs().maxCoeff();
    if (!(scale > 0.0) || !close(I, I.transpose(), scale) || Eigen::LLT<Mat3>(I).info() != Eigen::Success)
      bad(i, "inertia is not symmetric positive definite");
    // The inverse and ω = I_w⁻¹ (I_w ω) (sync_angular_momentum()) are exact to the inertia's
    // condition number times the rounding: a needle's 10^10 stays loadable.
    const double cond = std::max(1.0, scale * Ib_inv.cwiseAbs().maxCoeff());
    if (!close(I * Ib_inv, Mat3::Identity(), cond)) bad(i, "inverse inertia is not the inverse of its inertia");
    if (r.asleep[i] != 0) {
      if (r.inv_mass[i] != 0.0 || !Iw_inv.isZero(0.0))
        bad(i, "asleep with a non-zero inverse mass or world inverse inertia");
      continue;
    }
    if (!close(Vec3::Constant(r.inv_mass[i] * m), Vec3::Ones(), 1.0)) bad(i, "inverse mass is not 1 / mass");
    const Mat3 R = r.orientation[i].toRotationMatrix();
    if (!close(Iw_inv, R * Ib_inv * R.transpose(), Ib_inv.cwiseAbs().maxCoeff()))
      bad(i, "world inverse inertia is not R I_b^-1 R^T");
    const Vec3 w = Iw_inv * r.angular_momentum[i];
    if (!close(r.angular_velocity[i], w, cond * std::max(r.angular_velocity[i].cwiseAbs().maxCoeff(), w.cwiseAbs().maxCoeff())))
      bad(i, "angular velocity is not I_w^-1 L");
  }
}

void load_rigid(detail::RigidBodies& r, StateReader& in) {
  in.begin("RIGD");
  const std::size_t n = r.size();
  in.count(n, "rigid bodies");
  in.array(r.position, n, "rigid positions");
  in.array(r.orientation, n, "rigid orientations");
  in.array(r.linear_velocity, n, "rigid velocities");
  in.array(r.angular_momentum, n, "rigid angular momenta");
  in.array(r.angular_velocity, n, "rigid angular velocities");
  in.array(r.mass, n, "rigid masses");
  in.array(r.inv_mass, n, "rigid inverse masses");
  in.array(r.inertia_body, n, "rigid inertias");
  in.array(r.inv_inertia_body, n, "rigid inverse inertias");
  in.array(r.inv_inertia_world, n, "rigid world inverse inertias");
  in.array(r.force, n, "rigid forces");
  in.array(r.torque, n, "rigid torques");
  in.array(r.linear_drag, n, "rigid drags");
  in.array(r.angular_drag, n, "rigid drags");
  in.array(r.bias_velocity, n, "rigid bias velocities");
  in.array(r.bias_angular_velocity, n, "rigid bias velocities");
  in.array(r.asleep, n, "rigid sleep flags");
  for (std::size_t k : {r.orientation.size(), r.linear_velocity.size(), r.angular_momentum.size(),
                        r.angular_velocity.size(), r.mass.size(), r.inv_mass.size(),
                        r.inertia_body.size(), r.inv_inertia_body.size(),
                        r.inv_inertia_world.size(), r.force.size(), r.torque.size(),
                        r.linear_drag.size(), r.angular_drag.size(), r.bias_velocity.size(),
                        r.bias_angular_velocity.size(), r.asleep.size()})
    if (k != n) throw StateError("state: rigid arrays do not hold " + std::to_string(n) + " bodies");
  // What a step integrates or derives is finite (the mass, inertia and drags: check_rigid()), then
  // the relations between the arrays hold.
  detail::require_finite(r.position, n, "rigid positions");
  detail::require_finite(r.orientation, n, "rigid orientations");
  detail::require_finite(r.linear_velocity, n, "rigid velocities");
  detail::require_finite(r.angular_momentum, n, "rigid angular momenta");
  detail::require_finite(r.angular_velocity, n, "rigid angular velocities");
  detail::require_finite(r.inv_mass, n, "rigid inverse masses");
  detail::require_finite(r.inv_inertia_body, n, "rigid inverse inertias");
  detail::require_finite(r.inv_inertia_world, n, "rigid world inverse inertias");
  detail::require_finite(r.force, n, "rigid forces");
  detail::require_finite(r.torque, n, "rigid torques");
  detail::require_finite(r.bias_velocity, n, "rigid bias velocities");
  detail::require_finite(r.bias_angular_velocity, n, "rigid bias angular velocities");
  check_rigid(r);
  in.end();
}

// --- contacts: last step's manifolds with their impulses (warm start), sleep bookkeeping -----

void save_contacts(const detail::BodyDynamics& d, StateWriter& out) {
  out.begin("CONT");
  // After a step, `previous` holds that step's manifolds (stage_bodies.cpp swaps them in).
  out.value(std::uint64_t(d.previous.size()));
  for (const detail::BodyManifold& m : d.previous) {
    out.value(m.key.body_a);
    out.value(m.key.shape_a);
    out.value(m.key.body_b);
    out.value(m.key.shape_b);
    out.value(m.key.sub);
    out.value(m.rigid_a);
    out.value(m.rigid_b);
    out.value(m.first_point);
    out.value(std::int32_t(m.manifold.count));
    out.value(m.manifold.normal);
    for (int k = 0; k < m.manifold.count; ++k) {
      const detail::ManifoldPoint& p = m.manifold.points[std::size_t(k)];
      out.value(p.point_a);
      out.value(p.point_b);
      out.value(p.separation);
      out.value(std::uint8_t(p.id.type_a));
      out.value(std::uint8_t(p.id.type_b));
      out.value(p.id.index_a);
      out.value(p.id.index_b);
      out.value(p.normal_impulse);
      out.value(p.tangent_impulse);
    }
  }
  out.array(d.rest_time);
  out.array(d.island);
  out.end();
}

void load_contacts(detail::BodyDynamics& d, StateReader& in) {
  in.begin("CONT");
  // A manifold without points: its key, rigid indices, first point, count and normal.
  constexpr std::size_t kLeast = 2 * sizeof(std::uint64_t) + 3 * sizeof(std::uint32_t) +
                                 3 * sizeof(std::uint32_t) + sizeof(std::int32_t) + sizeof(Vec3);
  d.previous.assign(in.records(kLeast, "contact manifolds"), detail::BodyManifold{});
  for (detail::BodyManifold& m : d.previous) {
    in.value(m.key.body_a);
    in.value(m.key.shape_a);
    in.value(m.key.body_b);
    in.value(m.key.shape_b);
    in.value(m.key.sub);
    in.value(m.rigid_a);
    in.value(m.rigid_b);
    in.value(m.first_point);
    const auto count = in.value<std::int32_t>();
    if (count < 0 || count > detail::kMaxManifoldPoints) throw StateError("state: a manifold has a bad point count");
    m.manifold.count = count;
    in.value(m.manifold.normal);
    if (!(std::abs(m.manifold.normal.norm() - 1.0) <= 1e-6))
      throw StateError("state: a contact manifold's normal is not a unit vector");
    for (int k = 0; k < count; ++k) {
      detail::ManifoldPoint& p = m.manifold.points[std::size_t(k)];
      in.value(p.point_a);
      in.value(p.point_b);
      in.value(p.separation);
      p.id.type_a = detail::FeatureType(in.value<std::uint8_t>());
      p.id.type_b = detail::FeatureType(in.value<std::uint8_t>());
      in.value(p.id.index_a);
      in.value(p.id.index_b);
      in.value(p.normal_impulse);
      in.value(p.tangent_impulse);
      for (const Vec3* v : {&p.point_a, &p.point_b, &p.tangent_impulse})
        detail::require_finite(*v, "a contact point");
      detail::require_finite(p.separation, "a contact point's separation");
      // The solver clamps the accumulated normal impulse to >= 0 (rigid/contact_solver.cpp).
      if (!(std::isfinite(p.normal_impulse) && p.normal_impulse >= 0.0))
        throw StateError("state: a contact point's normal impulse is not a finite number >= 0");
    }
  }
  d.manifolds.clear();
  d.points.clear();
  in.array(d.rest_time, d.rigid.size(), "rest times");
  detail::require_finite(d.rest_time, d.rest_time.size(), "rest times");
  in.array(d.island, d.rigid.size(), "islands");
  in.end();
}

// --- joints: broken or not, last step's force and torque ------------------------------------

void save_joints(const WorldState& w, StateWriter& out) {
  out.begin("JOIN");
  out.value(std::uint64_t(w.joints.size()));
  for (const detail::JointEntry& j : w.joints.dense()) {
    out.value(std::uint8_t(j.broken));
    out.value(j.reading.force);
    out.value(j.reading.torque);
    out.value(std::uint8_t(j.reading.broken));
  }
  out.end();
}

void load_joints(WorldState& w, StateReader& in) {
  in.begin("JOIN");
  in.count(w.joints.size(), "joints");
  for (detail::JointEntry& j : w.joints.dense()) {
    j.broken = in.value<std::uint8_t>() != 0;
    in.value(j.reading.force);
    in.value(j.reading.torque);
    j.reading.broken = in.value<std::uint8_t>() != 0;
    detail::require_finite(j.reading.force, "a joint's force");
    detail::require_finite(j.reading.torque, "a joint's torque");
  }
  in.end();
}

// --- particle systems ------------------------------------------------------------------------

/// `from_split` is written only for a system with sub-emitters (the only reader), so snapshots of
/// scenes without them are unchanged.
void save_store(const detail::ParticleStore& st, StateWriter& out, bool from_split) {
  const std::size_t n = st.count;
  out.value(std::uint64_t(n));
  out.array(st.position, 3 * n);
  out.array(st.velocity, 3 * n);
  out.array(st.prev_position, st.track_prev ? 3 * n : 0);
  out.array(st.color, 4 * n);
  out.array(st.radius, n);
  out.array(st.mass, n);
  out.array(st.age, n);
  out.array(st.lifetime, n);
  out.array(st.id, n);
  out.array(st.charge, st.has_charge ? n : 0);
  out.array(st.base_radius, n);
  out.array(st.tint, n);
  out.array(st.split_generation, n);
  out.array(st.split_countdown, n);
  if (from_split) out.array(st.from_split, n);
  out.array(st.rest, st.track_rest ? 4 * n : 0);
}

void load_store(detail::ParticleStore& st, StateReader& in, const std::string& name, bool from_split) {
  // The arrays were reserved for max_particles at registration: reading within that never
  // allocates.
  const std::size_t room = std::max(st.position.capacity() / 3, st.count);
  const auto n64 = in.value<std::uint64_t>();
  if (n64 > room)
    throw StateError("state: particle system '" + name + "' holds " + std::to_string(n64) +
                     " particles, this world has room for " + std::to_string(room));
  const std::size_t n = std::size_t(n64);
  st.count = n;
  in.array(st.position, 3 * n, "particle positions");
  in.array(st.velocity, 3 * n, "particle velocities");
  in.array(st.prev_position, st.track_prev ? 3 * n : 0, "particle start positions");
  in.array(st.color, 4 * n, "particle colours");
  in.array(st.radius, n, "particle radii");
  in.array(st.mass, n, "particle masses");
  in.array(st.age, n, "particle ages");
  in.array(st.lifetime, n, "particle lifetimes");
  in.array(st.id, n, "particle ids");
  in.array(st.charge, st.has_charge ? n : 0, "particle charges");
  in.array(st.base_radius, n, "particle base radii");
  in.array(st.tint, n, "particle tints");
  in.array(st.split_generation, n, "particle split generations");
  in.array(st.split_countdown, n, "particle split countdowns");
  if (from_split) in.array(st.from_split, n, "particle split origins");
  else st.from_split.assign(n, 0);
  in.array(st.rest, st.track_rest ? 4 * n : 0, "particle rest states");
  if (st.track_memo) {  // the collision pass's cache (collide_memo.hpp): no entry for anyone
    st.memo.assign(detail::kMemoStride * n, 0.0f);
    st.memo_epoch.assign(n, 0u);
  }
  const bool ok = st.position.size() == 3 * n && st.velocity.size() == 3 * n &&
                  st.prev_position.size() == (st.track_prev ? 3 * n : 0) && st.color.size() == 4 * n &&
                  st.radius.size() == n && st.mass.size() == n && st.age.size() == n &&
                  st.lifetime.size() == n && st.id.size() == n &&
                  st.charge.size() == (st.has_charge ? n : 0) && st.base_radius.size() == n &&
                  st.tint.size() == n && st.split_generation.size() == n &&
                  st.split_countdown.size() == n && st.from_split.size() == n &&
                  st.rest.size() == (st.track_rest ? 4 * n : 0);
  if (!ok) throw StateError("state: particle system '" + name + "' arrays do not hold its " +
                            std::to_string(n) + " particles");
  const std::string of = "particle system '" + name + "': particle ";
  detail::require_finite(st.position, 3 * n, of + "positions");
  detail::require_finite(st.velocity, 3 * n, of + "velocities");
  detail::require_finite(st.prev_position, st.prev_position.size(), of + "start positions");
  detail::require_finite(st.color, 4 * n, of + "colours");
  detail::require_finite(st.radius, n, of + "radii");
  detail::require_finite(st.mass, n, of + "masses");
  detail::require_finite(st.age, n, of + "ages");
  detail::require_finite(st.charge, st.charge.size(), of + "charges");
  detail::require_finite(st.base_radius, n, of + "base radii");
  detail::require_finite(st.tint, n, of + "tints");
  detail::require_finite(st.rest, st.rest.size(), of + "rest states");
  for (std::size_t i = 0; i < n; ++i)  // +inf: a particle added without a lifetime
    if (!(st.lifetime[i] >= 0.0f))
      throw StateError("state: " + of + "lifetimes: value " + std::to_string(i) + " of " +
                       std::to_string(n) + " is " + format_number(st.lifetime[i]) +
                       ", expected a number >= 0");
}

void save_systems(const WorldState& w, StateWriter& out) {
  out.begin("PSYS");
  out.value(std::uint64_t(w.systems.size()));
  for (const detail::ParticleSystemState& ps : w.systems.dense()) {
    save_store(ps.store, out, !ps.sub_emitters.empty());
    out.value(ps.next_id);
    out.value(ps.emitter.scheduled);
    out.array(ps.emitter.bursts_fired);
    out.rng(ps.emitter.rng);
    out.rng(ps.split_rng);
    out.rng(ps.charge_rng);
    out.rng(ps.splash_rng);
    out.value(std::uint64_t(ps.springs.size()));  // springs die with their particles
    for (const SpringDef& s : ps.springs) {
      out.value(s.a);
      out.value(s.b);
      out.value(s.stiffness);
      out.value(s.damping);
      out.value(s.rest_length);
    }
    out.value(ps.integrator_state.next_h);
    out.value(ps.integrator_state.substeps);
    out.value(ps.integrator_state.rejected);
    out.value(ps.removed_inside);
  }
  w.particle_collider.save_warm(out);
  out.end();
}

void load_systems(WorldState& w, StateReader& in) {
  in.begin("PSYS");
  in.count(w.systems.size(), "particle systems");
  for (detail::ParticleSystemState& ps : w.systems.dense()) {
    load_store(ps.store, in, ps.def.name, !ps.sub_emitters.empty());
    // Beyond the divergence bounds the next step would stop the run (stage_integrate.cpp).
    // The start-of-step and rest positions too: the swept collision test starts from the one, a
    // sleeping particle is held at the other.
    const detail::ParticleStore& st = ps.store;
    const auto near = [&](const auto& column, std::size_t i) {
      return column.size() <= i || std::abs(column[i]) <= ps.forces.max_distance;
    };
    for (std::size_t i = 0; i < 3 * st.count; ++i)
      if (!(std::abs(st.position[i]) <= ps.forces.max_distance &&
            std::abs(st.velocity[i]) <= ps.forces.max_speed && near(st.prev_position, i) &&
            near(st.rest, 4 * (i / 3) + i % 3))) {
        std::ostringstream m;
        m << "state: particle system '" << ps.def.name << "': particle " << i / 3
          << " is beyond simulation.max_distance = " << ps.forces.max_distance
          << " m or simulation.max_speed = " << ps.forces.max_speed << " m/s";
        throw StateError(m.str());
      }
    in.value(ps.next_id);
    in.value(ps.emitter.scheduled);
    in.array(ps.emitter.bursts_fired, ps.def.emitter.bursts.size(), "emitter bursts");
    in.rng(ps.emitter.rng);
    in.rng(ps.split_rng);
    in.rng(ps.charge_rng);
    in.rng(ps.splash_rng);
    const auto springs = in.value<std::uint64_t>();
    if (springs > ps.springs.size())
      throw StateError("state: particle system '" + ps.def.name + "' holds " + std::to_string(springs) +
                       " springs, its definition " + std::to_string(ps.springs.size()));
    ps.springs.resize(std::size_t(springs));
    for (SpringDef& s : ps.springs) {
      in.value(s.a);
      in.value(s.b);
      in.value(s.stiffness);
      in.value(s.damping);
      in.value(s.rest_length);
    }
    in.value(ps.integrator_state.next_h);
    in.value(ps.integrator_state.substeps);
    in.value(ps.integrator_state.rejected);
    in.value(ps.removed_inside);
  }
  w.particle_collider.load_warm(in);
  in.end();
}

// --- cloths (cloth.cpp) ----------------------------------------------------------------------

void save_cloths(const WorldState& w, StateWriter& out) {
  out.begin("CLTH");
  out.value(std::uint64_t(w.cloths.size()));
  for (const Cloth& c : w.cloths.dense()) c.save_state(out);
  out.end();
}

void load_cloths(WorldState& w, StateReader& in) {
  in.begin("CLTH");
  in.count(w.cloths.size(), "cloths");
  for (Cloth& c : w.cloths.dense()) {
    c.load_state(in);
    // The divergence bounds, as for particles (stage_cloth.cpp stops a step beyond them).
    for (std::size_t i = 0; i < c.positions().size(); ++i)
      if (!(c.positions()[i].cwiseAbs().maxCoeff() <= w.def.max_distance &&
            c.velocities()[i].cwiseAbs().maxCoeff() <= w.def.max_speed))
        throw StateError("state: cloth '" + c.definition().name + "': vertex " + std::to_string(i) +
                         " is beyond simulation.max_distance or simulation.max_speed");
  }
  in.end();
}

}  // namespace

void World::save_state(std::string& out) const {
  const WorldState& w = *impl_;
  out.clear();
  StateWriter s(out);
  s.value(kMagic);
  s.value(detail::kStateFormat);
  save_clock(w, s);
  save_bodies(w, s);
  save_shapes(w, s);
  save_rigid(w.dyn.rigid, s);
  save_contacts(w.dyn, s);
  save_joints(w, s);
  save_systems(w, s);
  save_cloths(w, s);
}

void World::load_state(std::string_view bytes) {
  WorldState& w = *impl_;
  StateReader s(bytes);
  if (s.value<std::uint64_t>() != kMagic) throw StateError("state: not a simreel engine state");
  if (const auto f = s.value<std::uint32_t>(); f != detail::kStateFormat)
    throw StateError("state: format " + std::to_string(f) + ", this build reads format " +
                     std::to_string(detail::kStateFormat));
  if (!w.removed.empty())
    throw StateError("state: the world has unreported removals; load a state before removing objects");
  load_clock(w, s);
  load_bodies(w, s);
  load_shapes(w, s);
  load_rigid(w.dyn.rigid, s);
  load_contacts(w.dyn, s);
  load_joints(w, s);
  load_systems(w, s);
  load_cloths(w, s);
  if (!s.done()) throw StateError("state: " + std::to_string(bytes.size() - s.position()) + " bytes after the last section");
  w.moved.clear();
}

std::uint32_t World::state_format() { return detail::kStateFormat; }

std::vector<MovedObject> World::poses() const {
  const WorldState& w = *impl_;
  std::vector<MovedObject> out;
  const std::vector<detail::Body>& bodies = w.bodies.dense();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const detail::Body& b = bodies[i];
    if (!b.kinematic() && !b.dynamic()) continue;
    MovedObject m = b.report_pose(w.shapes);
    m.handle = w.bodies.handle(i);
    out.push_back(m);
  }
  return out;
}

}  // namespace simreel::sim
