// Triangle and edge contacts of cloth: collider features, self and cloth–cloth (Bridson, Fedkiw &
// Anderson 2002; Coutinho §2.2 AABB trees, §3.6.1 Coulomb friction, §3.7 two-way impulses,
// §3.9.2 cloth collisions). See cloth_contacts.hpp for what was chosen.
#include "cloth/cloth_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/contact_geometry.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim::detail {

namespace {

using Contact = ContactScratch::Contact;

constexpr int kRounds = 8;          // detect-and-resolve rounds before the failsafe
constexpr int kFailsafeRounds = 16;  // failsafe rounds (each only grows the set at rest)
constexpr double kShortEnough = 0.5;  // a round that found no pair closer than this × delta ends
constexpr double kColliderShortEnough = 0.1;  // the same for contacts with collider features

/// Is c the shape of a dynamic body (it logs impulses)?
bool dynamic_shape(const Collider& c, const BodyImpulses* impulses) {
  if (impulses == nullptr) return false;
  const std::size_t k = std::size_t(&c - impulses->shapes);
  return k < impulses->rigid.size() && impulses->rigid[k] != BodyImpulses::kNone;
}

/// Appends a collider's corners, centres, edges and axes as immovable nodes: start-of-step pose
/// (prev_center, prev_R) to end-of-step pose, each feature point moving on a straight line. A
/// dynamic body steps after the cloth (stages.hpp), so its features run from its current pose
/// along its current point velocities over the step h: the cloth is pushed ahead of where the
/// body is about to go, and the body takes the opposite impulse (Coutinho §3.7).
void add_features(const Collider& c, std::int32_t ci, bool dynamic, double h, ContactScratch& S) {
  auto node = [&](const Vec3& local, double r) {
    const Vec3 p = c.center + c.R * local;
    S.x0.push_back(dynamic ? p : Vec3(c.prev_center + c.prev_R * local));
    S.x.push_back(dynamic ? Vec3(p + h * c.point_velocity(p)) : p);
    S.winv.push_back(0.0);
    S.radius.push_back(r);
    S.cloth_of.push_back(-1 - ci);
    return std::uint32_t(S.x.size() - 1);
  };
  auto point = [&](std::uint32_t id, const Vec3& out = Vec3::Zero()) {
    S.points.push_back(id);
    S.point_collider.push_back(ci);
    S.point_out.push_back(c.R * out);
  };
  auto segment = [&](std::uint32_t a, std::uint32_t b, const Vec3& out = Vec3::Zero()) {
    S.segments.push_back({a, b});
    S.segment_collider.push_back(ci);
    S.segment_out.push_back(c.R * out);
  };
  switch (c.shape) {
    case Collider::Shape::plane: break;
    case Collider::Shape::sphere: point(node(Vec3::Zero(), c.radius)); break;
    case Collider::Shape::capsule:
    case Collider::Shape::cylinder: {
      // A cylinder's axis is shortened by its radius so its rounded stand-in stays inside it.
      const double hh = c.shape == Collider::Shape::capsule
                            ? c.half_height
                            : std::max(0.0, c.half_height - c.radius);
      const std::uint32_t a = node(Vec3(0, 0, -hh), c.radius), b = node(Vec3(0, 0, hh), c.radius);
      point(a);
      point(b);
      segment(a, b);
      break;
    }
    case Collider::Shape::box: {
      const Vec3& e = c.half_extents;
      std::uint32_t k[8];
      Vec3 corner[8];
      for (int i = 0; i < 8; ++i) {
        corner[i] = Vec3((i & 1) ? e.x() : -e.x(), (i & 2) ? e.y() : -e.y(), (i & 4) ? e.z() : -e.z());
        k[i] = node(corner[i], 0.0);
        point(k[i], corner[i].cwiseSign());
      }
      for (int i = 0; i < 8; ++i)
        for (int bit = 1; bit < 8; bit <<= 1)
          if (!(i & bit)) {
            Vec3 out = corner[i].cwiseSign();  // the two face normals meeting at the edge
            out[bit == 1 ? 0 : bit == 2 ? 1 : 2] = 0.0;
            segment(k[i], k[i | bit], out);
          }
      break;
    }
    case Collider::Shape::mesh: {
      const MeshShape& m = *c.mesh;
      const std::uint32_t first = std::uint32_t(S.x.size());
      for (std::size_t i = 0; i < m.sharp_vertices.size(); ++i)
        point(node(m.sharp_vertices[i], 0.0), m.sharp_vertex_out[i]);
      for (std::size_t i = 0; i < m.sharp_edges.size(); ++i)
        segment(first + m.sharp_edges[i][0], first + m.sharp_edges[i][1], m.sharp_edge_out[i]);
      break;
    }
  }
}

/// Does the collider's box, grown by its motion and `margin`, meet [lo, hi]?
bool collider_near(const Collider& c, const Vec3& lo, const Vec3& hi, double margin, bool dynamic,
                   double h) {
  if (c.shape == Collider::Shape::plane) return false;
  const double spin = dynamic ? h * c.angular_velocity.norm() : 0.0;
  const double motion =
      (dynamic ? h * c.velocity.norm() + spin * ((c.aabb_center - c.center).norm() + c.aabb_half.norm())
               : 0.0) +
      (c.center - c.prev_center).norm() +
      (c.R - c.prev_R).norm() * ((c.aabb_center - c.center).norm() + c.aabb_half.norm());
  const Vec3 grow = c.aabb_half + Vec3::Constant(margin + motion);
  return ((lo - c.aabb_center).array() <= grow.array()).all() &&
         ((c.aabb_center - hi).array() <= grow.array()).all();
}

/// Could the distance between the primitives made of points [0, split) and [split, 4) drop below
/// delta during the step, given their distances d0 at the start and d1 at the end? The distance
/// changes at most at rate L (m per step) = the largest relative displacement of a point of one
/// against a point of the other, so it stays >= (d0 + d1 - L) / 2.
bool may_meet(const Vec3 X0[4], const Vec3 X1[4], int split, double d0, double d1, double delta) {
  const Vec3 ref = X1[0] - X0[0];
  double la = 0.0, lb = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double m = (X1[k] - X0[k] - ref).norm();
    (k < split ? la : lb) = std::max(k < split ? la : lb, m);
  }
  return 0.5 * (d0 + d1 - (la + lb)) < delta;
}

/// Do [lo1, hi1] and [lo2, hi2] overlap?
bool boxes_meet(const Vec3& lo1, const Vec3& hi1, const Vec3& lo2, const Vec3& hi2) {
  return (lo1.array() <= hi2.array()).all() && (lo2.array() <= hi1.array()).all();
}

/// Vertex p against triangle (a, b, c) with wanted separation delta. On a contact fills `out`
/// (weights: +1 on p, minus the barycentric weights on the triangle) and returns true.
bool vertex_triangle(const ContactScratch& S, std::uint32_t p, std::uint32_t a, std::uint32_t b,
                     std::uint32_t c, double delta, const Vec3& outward, Contact& out) {
  const Vec3 X0[4] = {S.x0[a], S.x0[b], S.x0[c], S.x0[p]};
  const Vec3 X1[4] = {S.x[a], S.x[b], S.x[c], S.x[p]};
  Vec3 w = cg::closest_on_triangle(X1[3], X1[0], X1[1], X1[2]);
  Vec3 q = w[0] * X1[0] + w[1] * X1[1] + w[2] * X1[2];
  double d = (X1[3] - q).norm();
  bool crossed = false;
  const Vec3 n1 = (X1[1] - X1[0]).cross(X1[2] - X1[0]);
  if (d >= delta) {
    const Vec3 w0 = cg::closest_on_triangle(X0[3], X0[0], X0[1], X0[2]);
    const double d0 = (X0[3] - (w0[0] * X0[0] + w0[1] * X0[1] + w0[2] * X0[2])).norm();
    if (!may_meet(X0, X1, 3, d0, d, delta)) return false;
    double roots[3];
    const int nr = cg::coplanar_times(X0, X1, roots);
    for (int k = 0; k < nr && !crossed; ++k) {
      const double t = roots[k];
      const Vec3 at = cg::lerp(X0[0], X1[0], t), bt = cg::lerp(X0[1], X1[1], t),
                 ct = cg::lerp(X0[2], X1[2], t), pt = cg::lerp(X0[3], X1[3], t);
      const Vec3 wt = cg::closest_on_triangle(pt, at, bt, ct);
      if ((pt - (wt[0] * at + wt[1] * bt + wt[2] * ct)).norm() < delta) {
        crossed = true;
        w = wt;
      }
    }
    if (!crossed) return false;
  }
  // The side at the start of the step.
  const Vec3 q0 = w[0] * X0[0] + w[1] * X0[1] + w[2] * X0[2];
  const double side0 = (X0[3] - q0).dot(n1);
  const double n1len = n1.norm();
  const bool interior = w.minCoeff() > 1e-9;
  Vec3 n;
  const bool has_out = outward != Vec3::Zero();
  if (has_out) {
    // A solid's corner: the triangle stays outside, i.e. n (triangle -> corner) points inward.
    if (!crossed && d > 1e-9 * (delta + 1.0) && (X1[3] - q).dot(outward) < 0.0)
      n = (X1[3] - q) / d;
    else if (n1len > 0.0)
      n = (n1.dot(outward) > 0.0 ? -1.0 : 1.0) * n1 / n1len;
    else
      return false;
  } else if (!crossed && d > 1e-9 * (delta + 1.0) &&
             !(interior && n1len > 0.0 && ((X1[3] - q).dot(n1) < 0.0) != (side0 < 0.0))) {
    n = (X1[3] - q) / d;
  } else if (n1len > 0.0) {
    n = (side0 < 0.0 ? -1.0 : 1.0) * n1 / n1len;
  } else {
    return false;
  }
  out.id = {p, a, b, c};
  out.w = {1.0, -w[0], -w[1], -w[2]};
  out.count = 4;
  out.n = n;
  out.offset = 0.0;
  out.delta = delta;
  return true;
}

/// Edge (a, b) against edge (c, d): weights (1 - s, s) on the first, -(1 - u, u) on the second.
bool edge_edge(const ContactScratch& S, std::uint32_t a, std::uint32_t b, std::uint32_t c,
               std::uint32_t e, double delta, const Vec3& outward, Contact& out) {
  const Vec3 X0[4] = {S.x0[a], S.x0[b], S.x0[c], S.x0[e]};
  const Vec3 X1[4] = {S.x[a], S.x[b], S.x[c], S.x[e]};
  double s, u;
  cg::closest_segments(X1[0], X1[1], X1[2], X1[3], s, u);
  Vec3 pa = cg::lerp(X1[0], X1[1], s), pc = cg::lerp(X1[2], X1[3], u);
  double d = (pa - pc).norm();
  bool crossed = false;
  if (d >= delta) {
    double s0, u0;
    cg::closest_segments(X0[0], X0[1], X0[2], X0[3], s0, u0);
    const double d0 = (cg::lerp(X0[0], X0[1], s0) - cg::lerp(X0[2], X0[3], u0)).norm();
    if (!may_meet(X0, X1, 2, d0, d, delta)) return false;
    double roots[3];
    const int nr = cg::coplanar_times(X0, X1, roots);
    for (int k = 0; k < nr && !crossed; ++k) {
      const double t = roots[k];
      const Vec3 at = cg::lerp(X0[0], X1[0], t), bt = cg::lerp(X0[1], X1[1], t),
                 ct = cg::lerp(X0[2], X1[2], t), et = cg::lerp(X0[3], X1[3], t);
      double st, ut;
      cg::closest_segments(at, bt, ct, et, st, ut);
      if ((cg::lerp(at, bt, st) - cg::lerp(ct, et, ut)).norm() < delta) {
        crossed = true;
        s = st;
        u = ut;
      }
    }
    if (!crossed) return false;
  }
  const Vec3 pa0 = cg::lerp(X0[0], X0[1], s), pc0 = cg::lerp(X0[2], X0[3], u);
  const Vec3 m1 = (X1[1] - X1[0]).cross(X1[3] - X1[2]);
  const double m1len = m1.norm();
  const bool parallel = !(m1len > 1e-12 * (X1[1] - X1[0]).norm() * (X1[3] - X1[2]).norm());
  Vec3 n;
  if (outward != Vec3::Zero()) {
    // A solid's edge: the cloth edge stays on the outer side (n from the solid's edge outward).
    if (!crossed && d > 1e-9 * (delta + 1.0) && (pa - pc).dot(outward) > 0.0)
      n = (pa - pc) / d;
    else if (!parallel)
      n = (m1.dot(outward) < 0.0 ? -1.0 : 1.0) * m1 / m1len;
    else {
      const Vec3 dir = (X1[3] - X1[2]).normalized();
      n = (outward - outward.dot(dir) * dir).normalized();
    }
  } else if (!crossed && d > 1e-9 * (delta + 1.0)) {
    n = (pa - pc) / d;
  } else if (!parallel) {
    double side0 = (pa0 - pc0).dot(m1);
    if (side0 == 0.0) side0 = (pa - pc).dot(m1);
    n = (side0 < 0.0 ? -1.0 : 1.0) * m1 / m1len;
  } else {
    const double d0 = (pa0 - pc0).norm();
    if (!(d0 > 0.0)) return false;
    n = (pa0 - pc0) / d0;
  }
  out.id = {a, b, c, e};
  out.w = {1.0 - s, s, -(1.0 - u), -u};
  out.count = 4;
  out.n = n;
  out.offset = 0.0;
  out.delta = delta;
  return true;
}

/// Brings the contact's separation up to delta (see the header); returns how far it was short
/// of delta, as a fraction of delta (0 if it did not move).
double resolve(const Contact& k, ContactScratch& S, double h, std::vector<ContactCloth>& cloths,
             const std::vector<Collider>* colliders, BodyImpulses* impulses) {
  double sep = -k.offset, wsum = 0.0;
  Vec3 D = Vec3::Zero();  // relative displacement over the step
  for (int j = 0; j < k.count; ++j) {
    sep += k.w[j] * k.n.dot(S.x[k.id[j]]);
    wsum += k.w[j] * k.w[j] * S.winv[k.id[j]];
    D += k.w[j] * (S.x[k.id[j]] - S.x0[k.id[j]]);
  }
  const double push = k.delta - sep;
  // A contact already at its distance (within rounding) is left alone: rounds stop there.
  if (!(push > 1e-7 * k.delta) || !(wsum > 0.0)) return 0.0;
  Vec3 corr = push * k.n;  // wanted change of Σ w x
  const Vec3 Dt = D - D.dot(k.n) * k.n;
  const double dt = Dt.norm();
  if (dt > 0.0) corr -= std::min(1.0, k.friction * push / dt) * Dt;
  Vec3 momentum = Vec3::Zero();
  const bool kinematic = k.collider >= 0 && (*colliders)[std::size_t(k.collider)].moving &&
                         !dynamic_shape((*colliders)[std::size_t(k.collider)], impulses);
  for (int j = 0; j < k.count; ++j) {
    const std::uint32_t i = k.id[j];
    if (S.winv[i] == 0.0) continue;
    const Vec3 dx = (k.w[j] * S.winv[i] / wsum) * corr;
    S.x[i] += dx;
    const ContactCloth& C = cloths[std::size_t(S.cloth_of[i])];
    const std::uint32_t vi = i - S.offset[std::size_t(S.cloth_of[i])];
    (*C.v)[vi] += dx / h;
    if (kinematic && C.hit != nullptr) {
      (*C.hit)[vi] = 2;
      (*C.pushed_normal)[vi] = k.w[j] > 0.0 ? k.n : Vec3(-k.n);
    }
    momentum += C.vertex_mass * dx / h;
  }
  if (impulses != nullptr && k.collider >= 0) {
    const Collider& c = (*colliders)[std::size_t(k.collider)];
    Vec3 p = Vec3::Zero();
    for (int j = 0; j < k.count; ++j)
      if (S.winv[k.id[j]] == 0.0) p -= k.w[j] * S.x[k.id[j]];
    impulses->add(c, -momentum, p);
  }
  return push / k.delta;
}

}  // namespace

ContactStats collide_cloth_features(std::vector<ContactCloth>& cloths,
                                    const std::vector<Collider>* colliders, bool pairs, double h,
                                    ContactScratch& S, BodyImpulses* impulses) {
  ContactStats stats;
  // Nodes: the cloth vertices, then the features of the colliders near the cloths.
  S.x0.clear();
  S.x.clear();
  S.winv.clear();
  S.radius.clear();
  S.cloth_of.clear();
  S.offset.clear();
  S.edge_offset.clear();
  S.tri_offset.clear();
  S.points.clear();
  S.segments.clear();
  S.point_collider.clear();
  S.segment_collider.clear();
  S.point_out.clear();
  S.segment_out.clear();
  double max_thickness = 0.0;
  std::uint32_t ne = 0, nt = 0;
  for (std::size_t k = 0; k < cloths.size(); ++k) {
    const ContactCloth& C = cloths[k];
    S.offset.push_back(std::uint32_t(S.x.size()));
    S.edge_offset.push_back(ne);
    S.tri_offset.push_back(nt);
    ne += std::uint32_t(C.topo->edges.size() / 2);
    nt += std::uint32_t(C.topo->triangles.size() / 3);
    for (std::size_t i = 0; i < C.x->size(); ++i) {
      S.x0.push_back((*C.x0)[i]);
      S.x.push_back((*C.x)[i]);
      S.winv.push_back((*C.free)[i] ? 1.0 / C.vertex_mass : 0.0);
      S.radius.push_back(0.0);
      S.cloth_of.push_back(std::int32_t(k));
    }
    max_thickness = std::max(max_thickness, C.thickness);
  }
  const std::size_t cloth_nodes = S.x.size();
  if (cloth_nodes == 0 || nt == 0) return stats;
  Aabb all;
  for (std::size_t i = 0; i < cloth_nodes; ++i) {
    all.grow(S.x0[i]);
    all.grow(S.x[i]);
  }
  std::vector<std::int32_t> planes;  // (few) plane colliders, kept in the rounds
  if (colliders != nullptr)
    for (std::size_t c = 0; c < colliders->size(); ++c) {
      const Collider& col = (*colliders)[c];
      if (col.shape == Collider::Shape::plane) {
        planes.push_back(std::int32_t(c));
        continue;
      }
      const bool dynamic = dynamic_shape(col, impulses);
      if (collider_near(col, all.lo, all.hi, max_thickness, dynamic, h))
        add_features(col, std::int32_t(c), dynamic, h, S);
    }
  if (S.points.empty() && S.segments.empty() && !pairs) return stats;
  // Triangle boxes grow by the thickness; feature queries grow by their own radius.
  const double margin = max_thickness;

  // Self contacts use at most a quarter of the shortest rest edge, so neighbours in a flat
  // sheet never count as touching.
  std::vector<double> self_thickness(cloths.size());
  for (std::size_t k = 0; k < cloths.size(); ++k) {
    const ClothTopology& T = *cloths[k].topo;
    double shortest = std::numeric_limits<double>::infinity();
    for (std::size_t e = 0; e < T.edges.size(); e += 2)
      shortest = std::min(shortest, (T.local_rest[T.edges[e]] - T.local_rest[T.edges[e + 1]]).norm());
    self_thickness[k] = std::min(cloths[k].thickness, 0.25 * shortest);
  }
  // The farthest any pair reaches (pair_delta() below): the pairs' boxes grow by this, not by
  // the collider margin, which a thick cloth's collider contacts need and its self contacts do
  // not. Where the two agree (every demo) the pairs share the colliders' tree.
  double pair_margin = 0.0, others_margin = 0.0;
  std::size_t with_others = 0;  // (one such cloth has no other to meet)
  for (std::size_t k = 0; k < cloths.size(); ++k) {
    if (cloths[k].self) pair_margin = std::max(pair_margin, self_thickness[k]);
    if (cloths[k].others) {
      others_margin = std::max(others_margin, cloths[k].thickness);
      ++with_others;
    }
  }
  if (with_others >= 2) pair_margin = std::max(pair_margin, others_margin);
  const bool own_pair_tree = pairs && pair_margin < margin;
  auto tri_nodes = [&](std::uint32_t gt, std::uint32_t& k, std::uint32_t id[3]) {
    k = std::uint32_t(std::upper_bound(S.tri_offset.begin(), S.tri_offset.end(), gt) -
                      S.tri_offset.begin() - 1);
    const std::uint32_t t = gt - S.tri_offset[k];
    const auto& tris = cloths[k].topo->triangles;
    for (int j = 0; j < 3; ++j) id[j] = S.offset[k] + tris[3 * t + std::uint32_t(j)];
    return t;
  };
  auto pair_delta = [&](std::uint32_t k1, std::int32_t k2) {
    if (k2 < 0) return -1.0;
    if (std::uint32_t(k2) == k1) return cloths[k1].self ? self_thickness[k1] : -1.0;
    if (!cloths[k1].others || !cloths[std::size_t(k2)].others) return -1.0;
    return std::max(cloths[k1].thickness, cloths[std::size_t(k2)].thickness);
  };
  auto friction_of = [&](std::uint32_t k1, std::int32_t k2) {
    double f = cloths[k1].friction;
    if (k2 >= 0) f = 0.5 * (f + cloths[std::size_t(k2)].friction);
    return f;
  };

  for (int round = 0; round < kRounds + kFailsafeRounds; ++round) {
    // Swept boxes of the triangles, grown by the largest contact distance.
    S.boxes.resize(nt);
    if (own_pair_tree) S.pair_boxes.resize(nt);
    for (std::uint32_t gt = 0; gt < nt; ++gt) {
      std::uint32_t k, id[3];
      tri_nodes(gt, k, id);
      Aabb b;
      for (std::uint32_t i : id) {
        b.grow(S.x0[i]);
        b.grow(S.x[i]);
      }
      const Vec3 g = Vec3::Constant(margin);
      S.boxes[gt] = Triangle{b.lo - g, b.hi + g, b.lo - g, Vec3::Zero()};
      if (own_pair_tree) {
        const Vec3 gp = Vec3::Constant(pair_margin);
        S.pair_boxes[gt] = Triangle{b.lo - gp, b.hi + gp, b.lo - gp, Vec3::Zero()};
      }
    }
    const bool rebuilt = S.rebuild || S.bvh.size() != nt;
    if (rebuilt) {
      S.bvh = Bvh(S.boxes);
      S.rebuild = false;
    } else {
      S.bvh.refit(S.boxes);
    }
    if (own_pair_tree) {
      if (rebuilt || S.pair_bvh.size() != nt)
        S.pair_bvh = Bvh(S.pair_boxes);
      else
        S.pair_bvh.refit(S.pair_boxes);
    }
    const Bvh& bvh = S.bvh;
    // The pairs' tree and boxes (the colliders' where they reach as far).
    const Bvh& pair_bvh = own_pair_tree ? S.pair_bvh : S.bvh;
    const std::vector<Triangle>& pair_boxes = own_pair_tree ? S.pair_boxes : S.boxes;
    S.contacts.clear();
    Contact c;
    // Collider points against triangles.
    for (std::size_t f = 0; f < S.points.size(); ++f) {
      const std::uint32_t p = S.points[f];
      const Vec3 lo = S.x0[p].cwiseMin(S.x[p]) - Vec3::Constant(S.radius[p]);
      const Vec3 hi = S.x0[p].cwiseMax(S.x[p]) + Vec3::Constant(S.radius[p]);
      bvh.query(lo, hi, [&](std::uint32_t gt) {
        if (!boxes_meet(S.boxes[gt].a, S.boxes[gt].b, lo, hi)) return;  // leaves hold 4
        std::uint32_t k, id[3];
        tri_nodes(gt, k, id);
        if (vertex_triangle(S, p, id[0], id[1], id[2], cloths[k].thickness + S.radius[p],
                            S.point_out[f], c)) {
          c.friction = cloths[k].friction;
          c.collider = S.point_collider[f];
          S.contacts.push_back(c);
        }
      });
    }
    // Collider edges and axes against cloth edges.
    for (std::size_t f = 0; f < S.segments.size(); ++f) {
      const std::uint32_t a = S.segments[f][0], b = S.segments[f][1];
      const Vec3 lo = S.x0[a].cwiseMin(S.x[a]).cwiseMin(S.x0[b]).cwiseMin(S.x[b]) -
                      Vec3::Constant(S.radius[a]);
      const Vec3 hi = S.x0[a].cwiseMax(S.x[a]).cwiseMax(S.x0[b]).cwiseMax(S.x[b]) +
                      Vec3::Constant(S.radius[a]);
      bvh.query(lo, hi, [&](std::uint32_t gt) {
        if (!boxes_meet(S.boxes[gt].a, S.boxes[gt].b, lo, hi)) return;  // leaves hold 4
        std::uint32_t k, id[3];
        const std::uint32_t t = tri_nodes(gt, k, id);
        const ClothTopology& T = *cloths[k].topo;
        for (int j = 0; j < 3; ++j) {
          const std::uint32_t e = T.triangle_edges[3 * t + std::uint32_t(j)];
          if (T.edge_triangle[e] != t) continue;  // tested with its first triangle
          const std::uint32_t ea = S.offset[k] + T.edges[2 * e], eb = S.offset[k] + T.edges[2 * e + 1];
          if (edge_edge(S, ea, eb, a, b, cloths[k].thickness + S.radius[a], S.segment_out[f], c)) {
            c.friction = cloths[k].friction;
            c.collider = S.segment_collider[f];
            S.contacts.push_back(c);
          }
        }
      });
    }
    // Cloth against cloth: the tree against itself gives the pairs of triangles whose boxes
    // meet; each pair tests the vertices and edges its triangles own (the first triangle holding
    // them) against the other: every vertex–triangle and edge–edge pair once, as the queries
    // per vertex and per edge did, at a fraction of the traversals.
    if (pairs) {
      S.edge_lo.resize(ne);
      S.edge_hi.resize(ne);
      for (std::uint32_t k = 0; k < cloths.size(); ++k) {
        const ClothTopology& T = *cloths[k].topo;
        for (std::uint32_t e = 0; 2 * e < T.edges.size(); ++e) {
          const std::uint32_t a = S.offset[k] + T.edges[2 * e], b = S.offset[k] + T.edges[2 * e + 1];
          S.edge_lo[S.edge_offset[k] + e] = S.x0[a].cwiseMin(S.x[a]).cwiseMin(S.x0[b]).cwiseMin(S.x[b]);
          S.edge_hi[S.edge_offset[k] + e] = S.x0[a].cwiseMax(S.x[a]).cwiseMax(S.x0[b]).cwiseMax(S.x[b]);
        }
      }
      // Vertices owned by triangle t1 (of cloth k1, nodes id1) against triangle g2.
      auto vertices_against = [&](std::uint32_t t1, std::uint32_t k1, const std::uint32_t id1[3],
                                  std::uint32_t g2, const std::uint32_t id2[3], double delta,
                                  double friction) {
        const ClothTopology& T1 = *cloths[k1].topo;
        for (int j = 0; j < 3; ++j) {
          const std::uint32_t p = id1[j];
          if (T1.vertex_triangle[p - S.offset[k1]] != t1) continue;
          if (id2[0] == p || id2[1] == p || id2[2] == p) continue;
          if (S.winv[p] + S.winv[id2[0]] + S.winv[id2[1]] + S.winv[id2[2]] == 0.0) continue;
          const Vec3 lo = S.x0[p].cwiseMin(S.x[p]), hi = S.x0[p].cwiseMax(S.x[p]);
          if (!boxes_meet(pair_boxes[g2].a, pair_boxes[g2].b, lo, hi)) continue;
          if (vertex_triangle(S, p, id2[0], id2[1], id2[2], delta, Vec3::Zero(), c)) {
            c.friction = friction;
            c.collider = -1;
            S.contacts.push_back(c);
          }
        }
      };
      pair_bvh.self_pairs([&](std::uint32_t g1, std::uint32_t g2) {
        if (!boxes_meet(pair_boxes[g1].a, pair_boxes[g1].b, pair_boxes[g2].a, pair_boxes[g2].b)) return;
        std::uint32_t k1, k2, id1[3], id2[3];
        const std::uint32_t t1 = tri_nodes(g1, k1, id1), t2 = tri_nodes(g2, k2, id2);
        const double delta = pair_delta(k1, std::int32_t(k2));
        if (!(delta > 0.0)) return;
        const double friction = friction_of(k1, std::int32_t(k2));
        vertices_against(t1, k1, id1, g2, id2, delta, friction);
        vertices_against(t2, k2, id2, g1, id1, delta, friction);
        const ClothTopology& T1 = *cloths[k1].topo;
        const ClothTopology& T2 = *cloths[k2].topo;
        const Vec3 g = Vec3::Constant(delta);
        for (int j1 = 0; j1 < 3; ++j1) {
          const std::uint32_t e1 = T1.triangle_edges[3 * t1 + std::uint32_t(j1)];
          if (T1.edge_triangle[e1] != t1) continue;
          for (int j2 = 0; j2 < 3; ++j2) {
            const std::uint32_t e2 = T2.triangle_edges[3 * t2 + std::uint32_t(j2)];
            if (T2.edge_triangle[e2] != t2) continue;
            // The lower global edge first: edge_edge's weights and the normal's side are
            // those of the first edge, so the pair is tested the same way whichever triangle
            // owns which edge.
            std::uint32_t ka = k1, kb = k2, ea = e1, eb = e2;
            if (S.edge_offset[kb] + eb < S.edge_offset[ka] + ea) {
              std::swap(ka, kb);
              std::swap(ea, eb);
            }
            const ClothTopology& TA = *cloths[ka].topo;
            const ClothTopology& TB = *cloths[kb].topo;
            const std::uint32_t a = S.offset[ka] + TA.edges[2 * ea], b = S.offset[ka] + TA.edges[2 * ea + 1];
            const std::uint32_t ca = S.offset[kb] + TB.edges[2 * eb], cb = S.offset[kb] + TB.edges[2 * eb + 1];
            if (ca == a || ca == b || cb == a || cb == b) continue;
            if (S.winv[a] + S.winv[b] + S.winv[ca] + S.winv[cb] == 0.0) continue;
            const std::uint32_t ga = S.edge_offset[ka] + ea, gb = S.edge_offset[kb] + eb;
            if (!boxes_meet(S.edge_lo[gb] - g, S.edge_hi[gb] + g, S.edge_lo[ga], S.edge_hi[ga])) continue;
            if (edge_edge(S, a, b, ca, cb, delta, Vec3::Zero(), c)) {
              c.friction = friction;
              c.collider = -1;
              S.contacts.push_back(c);
            }
          }
        }
      });
      // A vertex in no triangle (a mesh cloth's loose vertex) has no owner: a query of its own.
      for (std::uint32_t p = 0; p < cloth_nodes; ++p) {
        const std::uint32_t kp = std::uint32_t(S.cloth_of[p]);
        if (cloths[kp].topo->vertex_triangle[p - S.offset[kp]] != std::numeric_limits<std::uint32_t>::max())
          continue;
        const Vec3 lo = S.x0[p].cwiseMin(S.x[p]), hi = S.x0[p].cwiseMax(S.x[p]);
        pair_bvh.query(lo, hi, [&](std::uint32_t gt) {
          if (!boxes_meet(pair_boxes[gt].a, pair_boxes[gt].b, lo, hi)) return;  // leaves hold 4
          std::uint32_t k, id[3];
          tri_nodes(gt, k, id);
          const double delta = pair_delta(kp, std::int32_t(k));
          if (!(delta > 0.0)) return;
          if (S.winv[p] + S.winv[id[0]] + S.winv[id[1]] + S.winv[id[2]] == 0.0) return;
          if (vertex_triangle(S, p, id[0], id[1], id[2], delta, Vec3::Zero(), c)) {
            c.friction = friction_of(kp, std::int32_t(k));
            c.collider = -1;
            S.contacts.push_back(c);
          }
        });
      }
    }
    // Planes: every cloth vertex stays `thickness` above them (the vertex pass's rule).
    const std::size_t pair_contacts = S.contacts.size();
    for (const std::int32_t pc : planes) {
      const Collider& pl = (*colliders)[std::size_t(pc)];
      for (std::uint32_t i = 0; i < cloth_nodes; ++i) {
        if (S.winv[i] == 0.0) continue;
        const ContactCloth& C = cloths[std::size_t(S.cloth_of[i])];
        if (pl.normal.dot(S.x[i] - pl.point) >= C.thickness) continue;
        c.id = {i, 0, 0, 0};
        c.w = {1.0, 0.0, 0.0, 0.0};
        c.count = 1;
        c.n = pl.normal;
        c.offset = pl.normal.dot(pl.point);
        c.delta = C.thickness;
        c.friction = C.friction;
        c.collider = pc;
        S.contacts.push_back(c);
      }
    }
    if (pair_contacts == 0) break;
    stats.rounds = std::size_t(round + 1);
    if (round < kRounds) {
      // Every detected contact is brought to its full distance; another round is needed only
      // if a cloth pair was found short by more than half of it (crossed or nearly: the rounds
      // exist to keep things from passing through, not to polish the thickness), or a collider
      // contact by more than a tenth (a body pushing the cloth keeps it at its thickness).
      double worst = 0.0;
      for (const Contact& k : S.contacts) {
        const double short_by = resolve(k, S, h, cloths, colliders, impulses);
        if (short_by > 0.0) {
          ++stats.contacts;
          worst = std::max(worst, k.collider >= 0 ? kShortEnough / kColliderShortEnough * short_by
                                                  : short_by);
          if (k.collider >= 0) {
            const Collider& col = (*colliders)[std::size_t(k.collider)];
            if (col.moving && !dynamic_shape(col, impulses)) stats.kinematic = true;
          }
        }
      }
      if (worst < kShortEnough) break;
      continue;
    }
    // Failsafe (cloth pairs only): every free cloth vertex of a remaining contact goes back to
    // its start position at rest.
    bool any = false;
    for (std::size_t q = 0; q < pair_contacts; ++q) {
      const Contact& k = S.contacts[q];
      if (k.collider >= 0) continue;
      for (int j = 0; j < k.count; ++j) {
        const std::uint32_t i = k.id[j];
        if (S.winv[i] == 0.0 || S.x[i] == S.x0[i]) continue;
        const std::size_t kc = std::size_t(S.cloth_of[i]);
        S.x[i] = S.x0[i];
        (*cloths[kc].v)[i - S.offset[kc]] = Vec3::Zero();
        ++stats.failsafe;
        any = true;
      }
    }
    if (!any) break;
  }
  // Write the corrected positions back.
  for (std::size_t k = 0; k < cloths.size(); ++k) {
    std::vector<Vec3>& x = *cloths[k].x;
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = S.x[S.offset[k] + i];
  }
  return stats;
}

}  // namespace simreel::sim::detail
