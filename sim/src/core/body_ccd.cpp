// Continuous collision of fast dynamic bodies (body_dynamics.hpp continuous_collisions): a sweep
// of each fast body from its start pose to its end pose against everything that is not itself
// swept, by conservative advancement (Mirtich 1996, §2.3.2) on GJK distances. Serial, in the
// rigid entries' order, so the result is the same at any thread count.
#include <algorithm>
#include <cmath>
#include <vector>

#include "collision/collider_impl.hpp"
#include "collision/gjk.hpp"
#include "collision/support.hpp"
#include "core/world_state.hpp"

namespace simreel::sim::detail {
namespace {

/// A body counts as fast when it may move more than this fraction of its thinnest shape's inner
/// radius in a step (Box2D v3's safety factor).
constexpr double kFastFraction = 0.5;
/// Conservative advancement stops within this of the target gap (m) or after this many rounds.
constexpr double kGapTolerance = 0.25 * kTimeOfImpactGap;
constexpr int kMaxRounds = 32;

/// (m) Half the thickness of a solid: the distance from its centre to its nearest face.
double inner_radius(const Collider& c) {
  switch (c.shape) {
    case Collider::Shape::sphere:
    case Collider::Shape::capsule: return c.radius;
    case Collider::Shape::cylinder: return std::min(c.radius, c.half_height);
    case Collider::Shape::box: return c.half_extents.minCoeff();
    default: return c.aabb_half.minCoeff();
  }
}

/// The extent of body b about its centre of mass x (m): its thinnest shape's inner radius and
/// the radius of a sphere about x holding all its shapes (from their world AABBs).
struct Extent {
  double thinnest = 0.0, reach = 0.0;
};
Extent extent_of(const WorldState& w, const Body& b, const Vec3& x) {
  Extent e{std::numeric_limits<double>::infinity(), 0.0};
  for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k) {
    const Collider& c = w.shapes[k];
    e.thinnest = std::min(e.thinnest, inner_radius(c));
    e.reach = std::max(e.reach, (c.aabb_center - x).norm() + c.aabb_half.norm());
  }
  return e;
}

/// (m) The smallest inner radius of body b's shapes.
double thinnest_of(const WorldState& w, const Body& b) {
  double t = std::numeric_limits<double>::infinity();
  for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k)
    t = std::min(t, inner_radius(w.shapes[k]));
  return t;
}

/// World pose of shape c of body b when b's centre of mass is at x with orientation q.
PosedShape shape_at(const Collider& c, const Body& b, const Vec3& x, const Quat& q) {
  const Transform body{x - q * b.local_com, q};
  const Transform s = c.offset_identity ? body : Transform{body.translation + body.rotation * c.offset.translation,
                                                           body.rotation * c.offset.rotation};
  return {convex_of(c), s.rotation.toRotationMatrix(), s.translation};
}

/// The swept body: its motion over the step and its extent.
struct Sweep {
  const Body* body = nullptr;
  Vec3 x0, x1;
  Quat q0, q1;
  double angle = 0.0;  ///< (rad) of the rotation from q0 to q1
  Extent extent;

  [[nodiscard]] Vec3 x(double t) const { return x0 + t * (x1 - x0); }
  [[nodiscard]] Quat q(double t) const { return q0.slerp(t, q1); }
  /// Upper bound of how far any point of the body moves over the step (m).
  [[nodiscard]] double bound() const { return (x1 - x0).norm() + angle * extent.reach; }
};

/// A target: a convex at a fixed pose, or a plane.
struct Target {
  bool plane = false;
  PosedShape convex;
  Vec3 point = Vec3::Zero(), normal = Vec3::UnitZ();
};

/// Distance (m) from the target to shape s (full shapes, negative when they overlap), and the
/// unit normal from the target towards s. `overlap` when GJK found the cores intersecting.
struct Gap {
  double distance = 0.0;
  Vec3 normal = Vec3::UnitZ();
  bool overlap = false;
};
Gap gap_of(const Target& t, const PosedShape& s) {
  if (t.plane) {
    const Vec3 deepest = s.support(-t.normal, ShapePart::full).world;
    return {t.normal.dot(deepest - t.point), t.normal, false};
  }
  const GjkResult g = gjk_distance(t.convex, s, ShapePart::core);
  if (g.status == GjkStatus::overlap) return {0.0, Vec3::UnitZ(), true};
  return {g.distance - t.convex.shape.core_radius() - s.shape.core_radius(), g.normal, false};
}

/// Conservative advancement (Mirtich 1996, §2.3.2) from the gap g at t = 0, gap_at(t) the gap
/// at a later time: t advances by (d - goal) / approach, where no point approaches faster than
/// the centres' relative motion over the step along the normal, -dx·n, plus `spin` (Σ θ r_max).
/// `bound` is how far any point may move relative to the target over the step and `thinnest`
/// the thinner side's inner radius; `half_space`: the target is a plane. Returns the time of
/// impact in [0, 1), or 1 for none.
template <class GapAt>
double advance(Gap g, const Vec3& dx, double spin, double bound, double thinnest, GapAt&& gap_at,
               bool half_space = false) {
  // Touching at the start: the discrete contacts have it. Cannot get deeper than half its inner
  // radius: the discrete contacts push it back out.
  if (g.overlap || !(g.distance > kGapTolerance)) return 1.0;
  if (bound <= g.distance + kFastFraction * thinnest) return 1.0;
  const double goal = std::min(kTimeOfImpactGap, 0.5 * g.distance);
  // As close at the start as the advancement would bring it (a gap up to twice the tolerance):
  // touching, like the case above. Stopped at t = 0 instead, the body would start the next step
  // from the same pose, stopped again, for ever, while its velocity grew (a 1 cm die on its edge,
  // a corner 0.3 mm above the ground, reached 11 m/s and 1350 rad/s standing still).
  if (g.distance <= goal + kGapTolerance) return 1.0;
  // Within the gap a stop leaves (the step's speculative contact holds it, letting it close the
  // gap, no more): swept only if it still ends the step deeper in than that gap. Swept every
  // step, each stop halfway closer, a rod tipping over about the end it had landed on never
  // counted as touching; it was stopped early in every step while gravity and its spin went on
  // growing (97 % of its energy gained at 1/60 s). A box the soft step's contact lets into a wall
  // at 100 m/s is still stopped short of it. A plane (`half_space`) has no far side to pass
  // through: its contact pushes whatever ends the step below it back up, and the soft step's,
  // letting a tipping rod's end sink a few mm, had it swept again (13-79 % gained at 1/60 s).
  if (g.distance <= kTimeOfImpactGap + kGapTolerance) {
    if (half_space) return 1.0;
    const Gap end = gap_at(1.0);
    if (!end.overlap && end.distance > -kTimeOfImpactGap) return 1.0;
  }
  double t = 0.0;
  for (int round = 0; round < kMaxRounds; ++round) {
    if (g.overlap) return t;  // rounding past the target: stop here
    if (g.distance <= goal + kGapTolerance) return t;
    const double approach = -dx.dot(g.normal) + spin;
    if (!(approach > 0.0)) return 1.0;
    t += (g.distance - goal) / approach;
    if (t >= 1.0) return 1.0;
    g = gap_at(t);
  }
  return t;
}

/// Time of impact in [0, 1) of shape c of the swept body against `target`, or 1 for none.
/// `face`, for a mesh triangle, is its unit normal (world).
double time_of_impact(const Sweep& sw, const Collider& c, const Target& target, const Vec3* face = nullptr) {
  const Body& b = *sw.body;
  if (face != nullptr) {
    // A triangle is crossed only by a body whose centre goes towards its plane by a good part of
    // its thickness; one sliding along a tessellated floor meets each next triangle's edge at
    // distance zero and would be stopped at every seam (Box2D v3 filters its segments alike).
    const Vec3 p = target.convex.translation + target.convex.rotation * target.convex.shape.vertices[0];
    const double s0 = face->dot(sw.x0 - p), s1 = face->dot(sw.x1 - p);
    if ((s0 >= 0.0 ? s0 - s1 : s1 - s0) < kFastFraction * sw.extent.thinnest) return 1.0;
  }
  return advance(gap_of(target, shape_at(c, b, sw.x0, sw.q0)), sw.x1 - sw.x0,
                 sw.angle * sw.extent.reach, sw.bound(), sw.extent.thinnest,
                 [&](double t) { return gap_of(target, shape_at(c, b, sw.x(t), sw.q(t))); }, target.plane);
}

/// Time of impact in [0, 1) of shape ca of swept body a against shape cb of swept body b, both
/// moving over the step, or 1 for none: advance() on their relative motion, the two bodies'
/// spins added.
double pair_time_of_impact(const Sweep& a, const Collider& ca, const Sweep& b, const Collider& cb) {
  const auto gap_at = [&](const Vec3& xa, const Quat& qa, const Vec3& xb, const Quat& qb) {
    Target target;
    target.convex = shape_at(cb, *b.body, xb, qb);
    return gap_of(target, shape_at(ca, *a.body, xa, qa));  // normal from b towards a
  };
  return advance(gap_at(a.x0, a.q0, b.x0, b.q0), (a.x1 - a.x0) - (b.x1 - b.x0),
                 a.angle * a.extent.reach + b.angle * b.extent.reach, a.bound() + b.bound(),
                 std::min(a.extent.thinnest, b.extent.thinnest),
                 [&](double t) { return gap_at(a.x(t), a.q(t), b.x(t), b.q(t)); });
}

}  // namespace

void begin_continuous(WorldState& w, double h) {
  BodyDynamics& d = w.dyn;
  RigidBodies& r = d.rigid;
  const std::size_t n = r.size();
  d.start_position.assign(r.position.begin(), r.position.end());
  d.start_orientation.assign(r.orientation.begin(), r.orientation.end());
  d.fast.assign(n, 0);
  if (!d.continuous) return;
  for (const Body& b : w.bodies.dense()) {
    if (!b.dynamic() || !r.is_dynamic(b.rigid)) continue;
    const std::uint32_t i = b.rigid;
    const Extent e = extent_of(w, b, r.position[i]);
    const double reach = h * (r.linear_velocity[i].norm() + r.angular_velocity[i].norm() * e.reach);
    d.fast[i] = reach > kFastFraction * e.thinnest ? 1 : 0;
  }
}

void continuous_collisions(WorldState& w, double h) {
  BodyDynamics& d = w.dyn;
  if (!d.continuous) return;
  RigidBodies& r = d.rigid;
  std::vector<Body>& bodies = w.bodies.dense();
  // Which bodies sweep: awake, dynamic, not jointed, moving more than a quarter of their
  // thickness. Kept in `fast` (its start-of-step meaning is used up by now).
  std::vector<std::uint8_t>& sweeping = d.fast;
  std::fill(sweeping.begin(), sweeping.end(), 0);
  for (const JointBodies& j : d.joint_bodies)
    for (const std::uint32_t i : {j.a, j.b})
      if (i != kStaticBody && i < sweeping.size()) sweeping[i] = 2;  // jointed: never swept
  bool any = false;
  for (const Body& b : bodies) {
    if (!b.dynamic() || !r.is_dynamic(b.rigid) || sweeping[b.rigid] == 2) continue;
    const std::uint32_t i = b.rigid;
    const Sweep sw{&b, d.start_position[i], r.position[i], d.start_orientation[i], r.orientation[i],
                   d.start_orientation[i].angularDistance(r.orientation[i]),
                   extent_of(w, b, d.start_position[i])};
    if (sw.bound() > kFastFraction * sw.extent.thinnest) {
      sweeping[i] = 1;
      any = true;
    }
  }
  if (!any) return;
  // Bodies with a contact point this step (their velocity change is not the forces' alone).
  std::vector<std::uint8_t> touched(r.size(), 0);
  for (const ContactPoint& c : d.points)
    for (const std::uint32_t k : {c.body_a, c.body_b})
      if (k != kStaticBody && k < touched.size()) touched[k] = 1;
  const auto sweep_of = [&](const Body& b) {
    const std::uint32_t i = b.rigid;
    return Sweep{&b, d.start_position[i], r.position[i], d.start_orientation[i], r.orientation[i],
                 d.start_orientation[i].angularDistance(r.orientation[i]),
                 extent_of(w, b, d.start_position[i])};
  };
  // Two swept bodies meet at the first time of impact of their relative motion (two bullets
  // head on would otherwise pass through each other: neither is swept against the other, and the
  // step's motion outruns the contacts' margin). Found from the start and end poses before any
  // body is moved back, so the order of the bodies does not matter; each keeps the earliest.
  // Sweep and prune over the swept boxes along x (many fast bodies, such as an explosion's
  // debris, must not cost a test per pair); the result is a minimum, so the order is free.
  struct Swept {
    std::uint32_t body;
    Sweep sweep;
    Vec3 lo, hi;  ///< box of the swept sphere (start and end centres grown by reach and gap)
  };
  std::vector<Swept> swept;
  for (std::uint32_t bi = 0; bi < bodies.size(); ++bi) {
    if (!bodies[bi].dynamic() || sweeping[bodies[bi].rigid] != 1) continue;
    const Sweep sw = sweep_of(bodies[bi]);
    const Vec3 grow = Vec3::Constant(sw.extent.reach + kSpeculativeMargin);
    const Vec3 lo = sw.x0.cwiseMin(sw.x1) - grow, hi = sw.x0.cwiseMax(sw.x1) + grow;
    // A body whose step blew up is reported after this stage (stage_bodies.cpp); a NaN key
    // would break the sort's ordering.
    if (!(lo.allFinite() && hi.allFinite())) continue;
    swept.push_back(Swept{bi, sw, lo, hi});
  }
  std::sort(swept.begin(), swept.end(), [](const Swept& p, const Swept& q) {
    return p.lo.x() != q.lo.x() ? p.lo.x() < q.lo.x() : p.body < q.body;
  });
  std::vector<double> pair_toi(r.size(), 1.0);
  for (std::size_t u = 0; u < swept.size(); ++u) {
    const Swept& a = swept[u];
    for (std::size_t v = u + 1; v < swept.size() && swept[v].lo.x() <= a.hi.x(); ++v) {
      const Swept& b = swept[v];
      if ((a.hi.array() < b.lo.array()).any() || (b.hi.array() < a.lo.array()).any()) continue;
      // As against one moving body below: only when they could pass through each other.
      const Sweep &sa = a.sweep, &sb = b.sweep;
      if (!(sa.bound() + sb.bound() > sa.extent.thinnest + sb.extent.thinnest)) continue;
      if (no_collide(d, a.body, b.body)) continue;
      const Body &ba = bodies[a.body], &bb = bodies[b.body];
      double t = 1.0;
      for (std::uint32_t ka = ba.first_shape; ka < ba.first_shape + ba.shape_count; ++ka)
        for (std::uint32_t kb = bb.first_shape; kb < bb.first_shape + bb.shape_count; ++kb)
          t = std::min(t, pair_time_of_impact(sa, w.shapes[ka], sb, w.shapes[kb]));
      pair_toi[ba.rigid] = std::min(pair_toi[ba.rigid], t);
      pair_toi[bb.rigid] = std::min(pair_toi[bb.rigid], t);
    }
  }
  for (std::uint32_t bi = 0; bi < bodies.size(); ++bi) {
    const Body& b = bodies[bi];
    if (!b.dynamic() || sweeping[b.rigid] != 1) continue;
    const std::uint32_t i = b.rigid;
    const Sweep sw = sweep_of(b);
    // The swept sphere's box (start and end centres grown by the reach and the gap).
    const Vec3 grow = Vec3::Constant(sw.extent.reach + kSpeculativeMargin);
    const Vec3 lo = sw.x0.cwiseMin(sw.x1) - grow, hi = sw.x0.cwiseMax(sw.x1) + grow;
    double toi = pair_toi[i];
    for (std::uint32_t bj = 0; bj < bodies.size(); ++bj) {
      if (bj == bi) continue;
      const Body& o = bodies[bj];
      const bool moves = o.dynamic() && r.is_dynamic(o.rigid);
      if (moves && sweeping[o.rigid] == 1) continue;  // two swept bodies: pair_toi above
      // A moving body is swept against only when this one could pass through it in one step
      // (deeper than both their half-thicknesses): stopping at every touch between bodies that
      // merely move quickly (a row of falling dominoes) would drop the rest of their steps and
      // bleed their energy away. Box2D sweeps non-bullets against static shapes only.
      if (moves && !(sw.bound() > sw.extent.thinnest + thinnest_of(w, o))) continue;
      if (no_collide(d, bi, bj)) continue;
      for (std::uint32_t k = o.first_shape; k < o.first_shape + o.shape_count; ++k) {
        const Collider& oc = w.shapes[k];
        Target target;
        if (oc.shape == Collider::Shape::plane) {
          target.plane = true;
          target.point = oc.point;
          target.normal = oc.normal;
        } else {
          // An awake dynamic body is met at its end pose; the others are where their shapes are.
          PosedShape at = moves ? shape_at(oc, o, r.position[o.rigid], r.orientation[o.rigid])
                                : PosedShape(convex_of(oc), oc.R, oc.center);
          // Its box: where it is, or a sphere about its box's centre carried to the end pose.
          const Vec3 c = moves ? Vec3(at.to_world(oc.R.transpose() * (oc.aabb_center - oc.center)))
                               : oc.aabb_center;
          const Vec3 half = moves ? Vec3::Constant(oc.aabb_half.norm()) : oc.aabb_half;
          if (((c + half).array() < lo.array()).any() || ((c - half).array() > hi.array()).any()) continue;
          if (oc.shape == Collider::Shape::mesh) {
            // Each triangle of the mesh under the swept box, as a 3-point hull.
            const Mat3 Rt = at.rotation.transpose();
            const Vec3 mc = Rt * (0.5 * (lo + hi) - at.translation);
            const Vec3 mh = Rt.cwiseAbs() * (0.5 * (hi - lo));
            oc.mesh->bvh.query(mc - mh, mc + mh, [&](std::uint32_t tri) {
              const Triangle& T = oc.mesh->triangles[tri];
              const std::array<Vec3, 3> local{T.a, T.b, T.c};
              Target tt;
              tt.convex = PosedShape(ConvexShape::hull(local), at.rotation, at.translation);
              const Vec3 face = at.rotation * T.normal;
              for (std::uint32_t s = b.first_shape; s < b.first_shape + b.shape_count; ++s)
                toi = std::min(toi, time_of_impact(sw, w.shapes[s], tt, &face));
            });
            continue;
          }
          target.convex = at;
        }
        for (std::uint32_t s = b.first_shape; s < b.first_shape + b.shape_count; ++s)
          toi = std::min(toi, time_of_impact(sw, w.shapes[s], target));
      }
    }
    if (toi < 1.0) {
      r.position[i] = sw.x(toi);
      r.orientation[i] = sw.q(toi).normalized();
      // In free flight its velocity is that of the time it is put back to: the forces' share of
      // the step it did not move taken off. Kept whole, a falling body stopped short of the
      // ground held the speed of the whole step at the height of part of it, and a ball of e = 0.8
      // dropped 1 m bounced 4 % higher than e² times the drop at 1/60 s. Touched by a contact
      // point, its velocity change is not the forces' alone (a resting contact cancels its
      // weight), so it keeps its velocity (Box2D's time loss).
      if (!touched[i]) {
        const double lost = (1.0 - toi) * h;
        r.linear_velocity[i] -= (lost * r.inv_mass[i]) * r.force[i];
        r.angular_momentum[i] -= lost * r.torque[i];
      }
      // The spin goes back with the pose: the angular momentum turned by the same rewind, so
      // the body-frame angular velocity, and with it the kinetic energy, is what it was.
      // Keeping the world-frame momentum instead read it against an inertia tensor turned away
      // from it: a needle (axial inertia 10⁴ times smaller) rewound by 0.2 rad while turning
      // about its short axis found most of that momentum along its axis and spun up 18,000
      // rad/s, 7 times its energy. About a fixed axis (the usual case) the turn leaves it as is.
      r.angular_momentum[i] = (r.orientation[i] * sw.q1.conjugate()) * r.angular_momentum[i];
      update_derived(r, i);
    }
  }
}

}  // namespace simreel::sim::detail
