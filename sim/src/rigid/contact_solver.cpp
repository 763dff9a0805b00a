// Sequential impulses with warm starting, Coulomb cone and split impulses (see
// contact_solver.hpp).
#include "rigid/contact_solver.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "rigid/integrate.hpp"

namespace simreel::sim::detail {
namespace {

/// The mass-related data of one side of a contact; the static world is all zeros.
struct Side {
  double inv_mass = 0.0;
  Mat3 inv_inertia = Mat3::Zero();
  Vec3 position = Vec3::Zero();
};

Side side_of(const RigidBodies& bodies, std::uint32_t i) {
  if (i == kStaticBody) return {};
  assert(i < bodies.size());
  return {bodies.inv_mass[i], bodies.inv_inertia_world[i], bodies.position[i]};
}

bool dynamic(const RigidBodies& bodies, std::uint32_t i) {
  return i != kStaticBody && bodies.is_dynamic(i);
}

using Row = ContactSolver::Row;
using Axis = ContactSolver::Axis;

Axis make_axis(const Side& a, const Side& b, bool move_a, bool move_b, const Vec3& ra,
               const Vec3& rb, const Vec3& d) {
  Axis x;
  x.d = d;
  x.ra_d = ra.cross(d);
  x.rb_d = rb.cross(d);
  x.ia_d = move_a ? Vec3(a.inv_inertia * x.ra_d) : Vec3::Zero();
  x.ib_d = move_b ? Vec3(b.inv_inertia * x.rb_d) : Vec3::Zero();
  const double k = a.inv_mass + b.inv_mass + x.ra_d.dot(x.ia_d) + x.rb_d.dot(x.ib_d);
  x.mass = k > 0.0 ? 1.0 / k : 0.0;
  return x;
}

/// The 2×2 tangent block K = J_t M⁻¹ J_tᵀ (its off-diagonal couples t1 and t2 through the
/// lever arms: large off a box's corner) inverted for the sticking solve, and one mass from its
/// trace (invariant under turning t1, t2 about n) for the sliding direction (friction_pair()).
void tangent_masses(Row& r) {
  const double k11 = 1.0 / r.t1.mass, k22 = 1.0 / r.t2.mass;
  const double k12 = r.t1.ra_d.dot(r.t2.ia_d) + r.t1.rb_d.dot(r.t2.ib_d);
  const double det = k11 * k22 - k12 * k12;
  r.sticking_mass[0] = det > 0.0 ? k22 / det : r.t1.mass;
  r.sticking_mass[1] = det > 0.0 ? -k12 / det : 0.0;
  r.sticking_mass[2] = det > 0.0 ? k11 / det : r.t2.mass;
  r.sliding_mass = 2.0 / (k11 + k22);
}

/// (m) How far the offset `radial` (perpendicular to the unit `axis`) moves under the swing
/// part of the turn (R - E = `turned`): the rotation that takes the axis where R takes it by the
/// shortest arc, with R's twist about the axis left out (R_swing x = c x + v × x + v (v·x)/(1+c),
/// c = a0·a1, v = a0 × a1). Zero when there is no axis.
Vec3 swing_moves(const Mat3& turned, const Vec3& axis, const Vec3& radial) {
  if (axis.isZero(0.0)) return Vec3::Zero();
  const Vec3 a1 = axis + turned * axis;
  const double c = axis.dot(a1);
  const Vec3 v = axis.cross(a1);
  // Turned over by more than ~170°: the shortest arc is ill-defined; the whole turn is then as
  // good a guess as any.
  if (c < -0.985) return turned * radial;
  return (c - 1.0) * radial + v.cross(radial) + v * (v.dot(radial) / (1.0 + c));
}

/// (v_b(p) - v_a(p)) · d from the arrays v and w (real or pseudo velocities).
[[gnu::always_inline]] inline double relative_speed(const Row& r, const Axis& x, const std::vector<Vec3>& v,
                      const std::vector<Vec3>& w) {
  double s = 0.0;
  if (r.b != kStaticBody) s += v[r.b].dot(x.d) + w[r.b].dot(x.rb_d);
  if (r.a != kStaticBody) s -= v[r.a].dot(x.d) + w[r.a].dot(x.ra_d);
  return s;
}

/// Applies the impulse λ d at b and -λ d at a to the arrays (v, w).
[[gnu::always_inline]] inline void apply(const Row& r, const Axis& x, double lambda, std::vector<Vec3>& v, std::vector<Vec3>& w) {
  if (r.move_a) {
    v[r.a] -= (r.inv_mass_a * lambda) * x.d;
    w[r.a] -= lambda * x.ia_d;
  }
  if (r.move_b) {
    v[r.b] += (r.inv_mass_b * lambda) * x.d;
    w[r.b] += lambda * x.ib_d;
  }
}

/// (N s) Radius of a contact's friction disc: μ_s λ_n while it sticks, μ λ_n once it slides.
double friction_bound(const ContactSolver::Row& r, double normal_impulse) {
  return (r.sliding ? r.friction : r.static_friction) * normal_impulse;
}

/// The accumulated tangent impulse pair (N s, along t1, t2) of contact r after one update, from
/// the pair before (p0, p1), the tangential relative velocities (s1, s2) and the disc radius.
/// Sticking: the pair that stops the slip at this point, K_t⁻¹ (the whole 2×2 block), kept
/// when it lies in the disc. Otherwise sliding: on the disc's rim along p − m̄ v_t, with one
/// mass m̄ for both directions, so a point that keeps slipping settles with its impulse against
/// the slip itself (Coulomb's maximum dissipation), whatever the tangent basis. Both rows from
/// the same velocities: solving t2 after t1's impulse let t1 leak into t2 through the lever arm,
/// and per-row masses turned the sliding impulse towards the heavier row — sliding along t1 met
/// 6-7 % less friction than along t2.
[[gnu::always_inline]] inline void friction_pair(const ContactSolver::Row& r, double p0, double p1,
                                                 double s1, double s2, double limit, double& f0,
                                                 double& f1) {
  f0 = p0 - (r.sticking_mass[0] * s1 + r.sticking_mass[1] * s2);
  f1 = p1 - (r.sticking_mass[1] * s1 + r.sticking_mass[2] * s2);
  if (f0 * f0 + f1 * f1 <= limit * limit) return;
  f0 = p0 - r.sliding_mass * s1;
  f1 = p1 - r.sliding_mass * s2;
  const double mag = std::sqrt(f0 * f0 + f1 * f1);
  const double scale = mag > 0.0 ? limit / mag : 0.0;
  f0 *= scale;
  f1 *= scale;
}

}  // namespace

void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  // Cross n with the coordinate axis it is least aligned with; 1/√3 guarantees one component
  // of that size, so the cross product never degenerates (Catto's b2PlaneSpace-like rule).
  if (std::abs(n.x()) >= 0.57735026918962576)
    t1 = Vec3(n.y(), -n.x(), 0.0).normalized();
  else
    t1 = Vec3(0.0, n.z(), -n.y()).normalized();
  t2 = n.cross(t1);
}

Vec3 relative_velocity(const RigidBodies& bodies, std::uint32_t a, std::uint32_t b,
                       const Vec3& p) {
  const Vec3 va = a == kStaticBody ? Vec3::Zero() : point_velocity(bodies, a, p);
  const Vec3 vb = b == kStaticBody ? Vec3::Zero() : point_velocity(bodies, b, p);
  return vb - va;
}

void ContactSolver::prepare(const RigidBodies& bodies, std::span<const ContactPoint> contacts,
                            double h, bool own_surface) {
  rows_.resize(contacts.size());  // keeps capacity: no allocation once grown
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactPoint& c = contacts[k];
    Row& r = rows_[k];
    const Side a = side_of(bodies, c.body_a), b = side_of(bodies, c.body_b);
    r.a = c.body_a;
    r.b = c.body_b;
    r.move_a = dynamic(bodies, c.body_a);
    r.move_b = dynamic(bodies, c.body_b);
    r.inv_mass_a = r.move_a ? a.inv_mass : 0.0;
    r.inv_mass_b = r.move_b ? b.inv_mass : 0.0;
    const Vec3 half = own_surface ? Vec3(0.5 * c.depth * c.normal) : Vec3::Zero();
    const Vec3 ra = c.body_a == kStaticBody ? Vec3::Zero() : Vec3(c.point + half - a.position);
    const Vec3 rb = c.body_b == kStaticBody ? Vec3::Zero() : Vec3(c.point - half - b.position);
    Vec3 t1, t2;
    tangent_basis(c.normal, t1, t2);
    r.n = make_axis(a, b, r.move_a, r.move_b, ra, rb, c.normal);
    r.t1 = make_axis(a, b, r.move_a, r.move_b, ra, rb, t1);
    r.t2 = make_axis(a, b, r.move_a, r.move_b, ra, rb, t2);
    tangent_masses(r);
    const Vec3 v_rel = relative_velocity(bodies, c.body_a, c.body_b, c.point);
    const double vn = v_rel.dot(c.normal);
    r.friction = c.friction;
    r.static_friction = std::max(c.static_friction, c.friction);
    // Sticking or sliding, from the slip at the step's start (before this step's forces): the
    // previous step's solve left a sticking contact at rest to its convergence.
    r.sliding = r.static_friction > r.friction &&
                (v_rel - vn * c.normal).squaredNorm() > settings_.stick_speed * settings_.stick_speed;
    if (c.depth < 0.0) {
      // Speculative contact (a gap of -depth): the bodies may close the gap in this step but no
      // more, so a contact found a little early neither stops them short nor lets them tunnel.
      // An approach that would close it within the step is an impact (a body stopped at its
      // time of impact meets the surface this way): it bounces as at contact.
      const double close = c.depth / h;
      r.target_vn = vn < close && vn < -settings_.restitution_threshold && c.restitution > 0.0
                        ? std::max(close, -c.restitution * vn)
                        : close;
    } else {
      // Newton's impact law v_n⁺ = -e v_n⁻ for an impact; 0 (stay in contact) when resting.
      r.target_vn = vn < -settings_.restitution_threshold ? -c.restitution * vn : 0.0;
    }
    r.target_bias = settings_.split_beta * std::max(c.depth - settings_.slop, 0.0) / h;
    r.bias_impulse = 0.0;
  }
}

void ContactSolver::warm_start(RigidBodies& bodies, std::span<ContactPoint> contacts) {
  assert(contacts.size() == rows_.size());
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    ContactPoint& c = contacts[k];
    if (!settings_.warm_start) {
      c.normal_impulse = c.tangent_impulse[0] = c.tangent_impulse[1] = 0.0;
      continue;
    }
    const Row& r = rows_[k];
    apply(r, r.n, c.normal_impulse, bodies.linear_velocity, bodies.angular_velocity);
    apply(r, r.t1, c.tangent_impulse[0], bodies.linear_velocity, bodies.angular_velocity);
    apply(r, r.t2, c.tangent_impulse[1], bodies.linear_velocity, bodies.angular_velocity);
  }
}

double ContactSolver::iterate_velocities(RigidBodies& bodies, std::span<ContactPoint> contacts) {
  assert(contacts.size() == rows_.size());
  auto& v = bodies.linear_velocity;
  auto& w = bodies.angular_velocity;
  double largest = 0.0;
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    const Row& r = rows_[k];
    ContactPoint& c = contacts[k];
    // Friction first, with the normal impulse of the previous sweep as its bound: the normal
    // row, solved last, then has the final say on penetration (Catto 2005).
    const double limit = friction_bound(r, c.normal_impulse);
    // Both tangent rows together, inside the Coulomb disc |λ_t| <= μ λ_n (friction_pair()).
    const double old0 = c.tangent_impulse[0], old1 = c.tangent_impulse[1];
    double t0, t1;
    friction_pair(r, old0, old1, relative_speed(r, r.t1, v, w), relative_speed(r, r.t2, v, w), limit, t0, t1);
    c.tangent_impulse[0] = t0;
    c.tangent_impulse[1] = t1;
    apply(r, r.t1, t0 - old0, v, w);
    apply(r, r.t2, t1 - old1, v, w);
    // Normal: reach target_vn, accumulated impulse clamped to >= 0 (Catto 2005).
    const double vn = relative_speed(r, r.n, v, w);
    const double old_n = c.normal_impulse;
    c.normal_impulse = std::max(old_n - r.n.mass * (vn - r.target_vn), 0.0);
    const double dn = c.normal_impulse - old_n;
    apply(r, r.n, dn, v, w);
    largest = std::max(largest, std::abs(dn));
  }
  return largest;
}

void ContactSolver::solve_positions(RigidBodies& bodies) {
  auto& v = bodies.bias_velocity;
  auto& w = bodies.bias_angular_velocity;
  for (int it = 0; it < settings_.position_iterations; ++it)
    for (Row& r : rows_) {
      if (r.target_bias <= 0.0 && r.bias_impulse <= 0.0) continue;
      const double vn = relative_speed(r, r.n, v, w);
      const double old = r.bias_impulse;
      r.bias_impulse = std::max(old - r.n.mass * (vn - r.target_bias), 0.0);
      apply(r, r.n, r.bias_impulse - old, v, w);
    }
}

void ContactSolver::finish(RigidBodies& bodies) const {
  for (const Row& r : rows_) {
    if (dynamic(bodies, r.a)) sync_angular_momentum(bodies, r.a);
    if (dynamic(bodies, r.b)) sync_angular_momentum(bodies, r.b);
  }
}

void ContactSolver::solve(RigidBodies& bodies, std::span<ContactPoint> contacts) {
  warm_start(bodies, contacts);
  for (int it = 0; it < settings_.velocity_iterations; ++it) iterate_velocities(bodies, contacts);
  solve_positions(bodies);
  finish(bodies);
}

void ContactSolver::prepare_soft(const RigidBodies& bodies, std::span<const ContactPoint> contacts,
                                 double h_sub) {
  prepare(bodies, contacts, h_sub, true);
  h_sub_ = h_sub;
  // Soft constraint of stiffness ω = 2π f, damping ratio ζ over the substep h (Catto 2024,
  // b2MakeSoft): bias rate ω / (2ζ + h ω), mass scale h ω (2ζ + h ω) / (1 + h ω (2ζ + h ω)),
  // impulse scale 1 / (1 + h ω (2ζ + h ω)). f is capped at a quarter of the substep rate.
  const double hertz = std::min(settings_.contact_hertz, 0.25 / h_sub);
  const double omega = 2.0 * 3.14159265358979323846 * hertz;
  const double a1 = 2.0 * settings_.damping_ratio + h_sub * omega;
  const double a2 = h_sub * omega * a1;
  const double a3 = 1.0 / (1.0 + a2);
  bias_rate_ = omega / a1;
  mass_scale_ = a2 * a3;
  impulse_scale_ = a3;

  const std::size_t n = bodies.size();
  start_x_.assign(bodies.position.begin(), bodies.position.end());
  start_q_.assign(bodies.orientation.begin(), bodies.orientation.end());
  moved_x_.resize(n);
  turned_.resize(n);
  soft_.resize(contacts.size());
  (void)n;
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactPoint& c = contacts[k];
    SoftRow& s = soft_[k];
    // Each side's arm to its own surface point (c.point is midway): in a deep overlap the
    // midpoint lies off a thin body, and the arm to it turned the push into spin about the
    // body's axis (a wire 4 cm into the ground got 8·10⁴ rad/s). The two points differ along n
    // only, so the pair's impulses still carry no net torque.
    // (prepare(own_surface) built the rows from the same arms.)
    s.ra = c.body_a == kStaticBody ? Vec3::Zero() : Vec3(c.point + 0.5 * c.depth * c.normal - bodies.position[c.body_a]);
    s.rb = c.body_b == kStaticBody ? Vec3::Zero() : Vec3(c.point - 0.5 * c.depth * c.normal - bodies.position[c.body_b]);
    s.arm_a = s.ra;
    s.arm_b = s.rb;
    // A round side's surface point under the contact is its centre -/+ radius along n: that
    // centre turns with the body, the point does not (0 · n leaves other shapes' arms as they are).
    s.turn_a = s.ra - c.round_a * c.normal - c.radial_a;
    s.turn_b = s.rb + c.round_b * c.normal - c.radial_b;
    s.axis_a = c.axis_a;
    s.axis_b = c.axis_b;
    s.radial_a = c.radial_a;
    s.radial_b = c.radial_b;
    s.separation = -c.depth;
    s.current = s.separation;
    s.restitution = c.restitution;
    const Vec3 v_rel = relative_velocity(bodies, c.body_a, c.body_b, c.point);
    s.approach = v_rel.dot(c.normal);
    Row& r = rows_[k];
    if (r.static_friction > r.friction)
      r.sliding = (v_rel - s.approach * c.normal).squaredNorm() >
                  settings_.soft_stick_speed * settings_.soft_stick_speed;
    s.max_normal = 0.0;
  }
  refreshed_q_.assign(bodies.orientation.begin(), bodies.orientation.end());
  refreshed_inertia_.assign(bodies.inv_inertia_world.begin(), bodies.inv_inertia_world.end());
}

void ContactSolver::refresh_soft(const RigidBodies& bodies) {
  const std::size_t n = bodies.size();
  stale_.assign(n, 0);
  // sin(θ/2) of the turn since the body's rows were computed; the inertia test catches what
  // changes it without a turn (a joint's geometric stiffness, JointSolver::stiffen_inertia).
  constexpr double kHalfTurn = 0.5 * kRefreshTurn;
  for (std::size_t i = 0; i < n; ++i) {
    if (!bodies.is_dynamic(i)) continue;
    const Quat dq = bodies.orientation[i] * refreshed_q_[i].conjugate();
    const Mat3& inertia = bodies.inv_inertia_world[i];
    const double moved = (inertia - refreshed_inertia_[i]).cwiseAbs().maxCoeff();
    if (dq.vec().squaredNorm() > kHalfTurn * kHalfTurn ||
        moved > kRefreshTurn * refreshed_inertia_[i].cwiseAbs().maxCoeff()) {
      stale_[i] = 1;
      refreshed_q_[i] = bodies.orientation[i];
      refreshed_inertia_[i] = inertia;
    }
  }
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    Row& r = rows_[k];
    if (!((r.move_a && stale_[r.a]) || (r.move_b && stale_[r.b]))) continue;
    const SoftRow& s = soft_[k];
    auto refresh = [&](Axis& x) {
      if (r.move_a) {
        x.ra_d = s.arm_a.cross(x.d);
        x.ia_d = bodies.inv_inertia_world[r.a] * x.ra_d;
      }
      if (r.move_b) {
        x.rb_d = s.arm_b.cross(x.d);
        x.ib_d = bodies.inv_inertia_world[r.b] * x.rb_d;
      }
      const double m = r.inv_mass_a + r.inv_mass_b + x.ra_d.dot(x.ia_d) + x.rb_d.dot(x.ib_d);
      x.mass = m > 0.0 ? 1.0 / m : 0.0;
    };
    refresh(r.n);
    refresh(r.t1);
    refresh(r.t2);
    tangent_masses(r);
  }
}

void ContactSolver::warm_start_soft(RigidBodies& bodies, std::span<ContactPoint> contacts) const {
  assert(contacts.size() == rows_.size());
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    ContactPoint& c = contacts[k];
    if (!settings_.warm_start) continue;
    const Row& r = rows_[k];
    apply(r, r.n, c.normal_impulse, bodies.linear_velocity, bodies.angular_velocity);
    apply(r, r.t1, c.tangent_impulse[0], bodies.linear_velocity, bodies.angular_velocity);
    apply(r, r.t2, c.tangent_impulse[1], bodies.linear_velocity, bodies.angular_velocity);
  }
}

void ContactSolver::track_separations(const RigidBodies& bodies) {
  // Each body's displacement and turn since prepare_soft, then each contact's separation from
  // them: the anchors are fixed in the bodies, so the separation follows them without a
  // narrow phase (the normal is held for the step).
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies.is_dynamic(i)) continue;
    moved_x_[i] = bodies.position[i] - start_x_[i];
    turned_[i] = (bodies.orientation[i] * start_q_[i].conjugate()).toRotationMatrix() - Mat3::Identity();
  }
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    const Row& r = rows_[k];
    SoftRow& s = soft_[k];
    Vec3 d = Vec3::Zero();
    if (r.move_b) {
      const Vec3 arm = turned_[r.b] * s.turn_b + swing_moves(turned_[r.b], s.axis_b, s.radial_b);
      s.arm_b = s.rb + arm;
      d += moved_x_[r.b] + arm;
    }
    if (r.move_a) {
      const Vec3 arm = turned_[r.a] * s.turn_a + swing_moves(turned_[r.a], s.axis_a, s.radial_a);
      s.arm_a = s.ra + arm;
      d -= moved_x_[r.a] + arm;
    }
    s.current = s.separation + d.dot(r.n.d);
  }
}

void ContactSolver::solve_soft(RigidBodies& bodies, std::span<ContactPoint> contacts, bool use_bias) {
  assert(contacts.size() == rows_.size());
  auto& v = bodies.linear_velocity;
  auto& w = bodies.angular_velocity;
  const double inv_h = 1.0 / h_sub_;
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    const Row& r = rows_[k];
    SoftRow& s = soft_[k];
    ContactPoint& c = contacts[k];
    const double sep = s.current;
    double bias = 0.0, mass_scale = 1.0, impulse_scale = 0.0;
    if (sep > 0.0) {
      bias = sep * inv_h;  // speculative: close the gap within the substep, no more
    } else if (use_bias) {
      bias = std::max(bias_rate_ * std::min(sep + settings_.soft_slop, 0.0), -settings_.max_push_speed);
      mass_scale = mass_scale_;
      impulse_scale = impulse_scale_;
    }
    // The two bodies' velocities in registers for the contact's three rows (one load and one
    // store per body instead of one per row).
    const bool has_a = r.a != kStaticBody, has_b = r.b != kStaticBody;
    Vec3 va = has_a ? v[r.a] : Vec3::Zero(), wa = has_a ? w[r.a] : Vec3::Zero();
    Vec3 vb = has_b ? v[r.b] : Vec3::Zero(), wb = has_b ? w[r.b] : Vec3::Zero();
    const double ima = r.move_a ? r.inv_mass_a : 0.0, imb = r.move_b ? r.inv_mass_b : 0.0;
    auto speed = [&](const Axis& x) { return vb.dot(x.d) + wb.dot(x.rb_d) - va.dot(x.d) - wa.dot(x.ra_d); };
    auto push = [&](const Axis& x, double lambda) {
      va -= (ima * lambda) * x.d;
      wa -= lambda * x.ia_d;  // zero unless a moves
      vb += (imb * lambda) * x.d;
      wb += lambda * x.ib_d;
    };
    // The normal first (soft, with the push-out bias when use_bias).
    const double vn = speed(r.n);
    const double old_n = c.normal_impulse;
    c.normal_impulse =
        std::max(old_n - r.n.mass * mass_scale * (vn + bias) - impulse_scale * old_n, 0.0);
    push(r.n, c.normal_impulse - old_n);
    // The approach speed for restitution: that of the substep where the contact first pushes
    // (a body falling through the step hits faster than it moved at the step's start).
    if (s.max_normal == 0.0 && c.normal_impulse > 0.0) s.approach = std::min(s.approach, vn);
    s.max_normal = std::max(s.max_normal, c.normal_impulse);
    // Then friction (no bias), bounded by this sweep's normal impulse (Box2D v3's order): the
    // warm start carries an impact's whole impulse into the next substep, and a bound from it
    // before the normal row has given it back let friction spin a 100 m/s box off a wall.
    const double limit = friction_bound(r, c.normal_impulse);
    // Both rows together, isotropic (friction_pair()).
    double f0, f1;
    friction_pair(r, c.tangent_impulse[0], c.tangent_impulse[1], speed(r.t1), speed(r.t2), limit, f0, f1);
    push(r.t1, f0 - c.tangent_impulse[0]);
    push(r.t2, f1 - c.tangent_impulse[1]);
    c.tangent_impulse[0] = f0;
    c.tangent_impulse[1] = f1;
    if (r.move_a) v[r.a] = va, w[r.a] = wa;
    if (r.move_b) v[r.b] = vb, w[r.b] = wb;
  }
}

void ContactSolver::restitution_soft(RigidBodies& bodies, std::span<ContactPoint> contacts) {
  auto& v = bodies.linear_velocity;
  auto& w = bodies.angular_velocity;
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    const Row& r = rows_[k];
    const SoftRow& s = soft_[k];
    if (s.restitution == 0.0 || s.approach > -settings_.restitution_threshold || s.max_normal == 0.0)
      continue;
    ContactPoint& c = contacts[k];
    const double vn = relative_speed(r, r.n, v, w);
    const double old_n = c.normal_impulse;
    c.normal_impulse = std::max(old_n - r.n.mass * (vn + s.restitution * s.approach), 0.0);
    apply(r, r.n, c.normal_impulse - old_n, v, w);
  }
}

void step_with_contacts(RigidBodies& bodies, ContactSolver& solver,
                        std::span<ContactPoint> contacts, double h, const Vec3& g) {
  apply_gravity(bodies, g);
  solver.prepare(bodies, contacts, h);
  integrate_velocities(bodies, h);
  solver.solve(bodies, contacts);
  integrate_positions(bodies, h);
  clear_forces(bodies);
}

}  // namespace simreel::sim::detail
