// Particles against cloth triangles (Coutinho §3.4 swept spheres, §3.6.1 impulses, §3.9.2 cloth
// collisions "follow the same principles").
#include "cloth/cloth_particles.hpp"

#include <algorithm>
#include <cmath>

#include "collision/narrow_phase.hpp"

namespace simreel::sim::detail {

namespace {

/// Barycentric weights of the point of triangle (a, b, c) nearest to p's projection on its
/// plane, clamped into the triangle (weights >= 0, sum 1).
Vec3 barycentric(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  const Vec3 e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
  const double d20 = d.dot(e0), d21 = d.dot(e1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 0.0)) return {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
  double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  v = std::max(v, 0.0);
  w = std::max(w, 0.0);
  double u = 1.0 - v - w;
  if (u < 0.0) {  // outside the hypotenuse: scale back onto it
    const double sum = v + w;
    v /= sum;
    w /= sum;
    u = 0.0;
  }
  return {u, v, w};
}

}  // namespace

std::size_t collide_particles_with_cloth(ParticleStore& s, double h, Cloth& cloth,
                                         ClothParticleScratch& scratch) {
  if (s.count == 0) return 0;
  const ClothDef& def = cloth.definition();
  const ClothView view = cloth.view();
  const std::vector<Vec3>& x = cloth.positions();
  const std::vector<Vec3>& x0 = cloth.start_positions();
  const std::vector<Vec3>& v = cloth.velocities();
  const std::size_t nt = view.triangle_count;
  const std::uint32_t* tri = view.triangles;
  if (nt == 0) return 0;

  // End-of-step triangles, their centroid shifts, the cloth's bounds and largest deformation.
  scratch.triangles.resize(nt);
  scratch.shift.resize(nt);
  Aabb bounds;
  double max_move = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    bounds.grow(x[i]);
    max_move = std::max(max_move, (x[i] - x0[i]).norm());
  }
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t i = tri[3 * t], j = tri[3 * t + 1], k = tri[3 * t + 2];
    Triangle& T = scratch.triangles[t];
    T.a = x[i];
    T.b = x[j];
    T.c = x[k];
    const Vec3 nrm = (T.b - T.a).cross(T.c - T.a);
    const double len = nrm.norm();
    T.normal = len > 0.0 ? Vec3(nrm / len) : Vec3::Zero();
    scratch.shift[t] = ((x[i] - x0[i]) + (x[j] - x0[j]) + (x[k] - x0[k])) / 3.0;
  }
  // Rebuilt every step: the cloth deforms (O(t log t), small next to the cloth's own solve).
  const Bvh bvh(scratch.triangles);
  scratch.impulse.assign(x.size(), Vec3::Zero());

  std::size_t contacts = 0;
  float* pos = s.position.data();
  float* vel = s.velocity.data();
  for (std::size_t p = 0; p < s.count; ++p) {
    const Vec3 p1(pos[3 * p], pos[3 * p + 1], pos[3 * p + 2]);
    const Vec3 v1(vel[3 * p], vel[3 * p + 1], vel[3 * p + 2]);
    const double dt = std::min(double(s.age[p]), h);
    const Vec3 p0 = s.track_prev ? Vec3(s.prev_position[3 * p], s.prev_position[3 * p + 1],
                                        s.prev_position[3 * p + 2])
                                 : Vec3(p1 - dt * v1);
    const double r = double(s.radius[p]) + def.thickness;
    const Vec3 grow = Vec3::Constant(r + max_move);
    const Vec3 lo = p0.cwiseMin(p1) - grow, hi = p0.cwiseMax(p1) + grow;
    if (!bounds.overlaps(lo, hi)) continue;
    SweepHit best;
    std::uint32_t best_t = 0;
    bvh.query(lo, hi, [&](std::uint32_t t) {
      const Vec3 a = p0 + scratch.shift[t];  // start in the frame moving with the triangle
      const double before = best.s;
      sweep_triangle(scratch.triangles[t], a, p1 - a, r, best);
      if (best.s < before) best_t = t;
    });
    if (!(best.s <= 1.0)) continue;

    const std::uint32_t ids[3] = {tri[3 * best_t], tri[3 * best_t + 1], tri[3 * best_t + 2]};
    const Triangle& T = scratch.triangles[best_t];
    const Vec3 w = barycentric(T.a, T.b, T.c, best.point);
    Vec3 v_tri = Vec3::Zero();
    double inv_m_tri = 0.0;
    for (int k = 0; k < 3; ++k) {
      v_tri += w[k] * v[ids[k]];
      inv_m_tri += w[k] * w[k] * cloth.inverse_mass(ids[k]);
    }
    const Vec3& n = best.normal;
    const Vec3 rel = v1 - v_tri;
    const double vn = rel.dot(n);
    if (!(vn < 0.0)) continue;  // already separating
    const double m_p = s.mass[p];
    const double inv_m = 1.0 / m_p + inv_m_tri;
    const double jn = -(1.0 + def.restitution) * vn / inv_m;
    const Vec3 vt = rel - vn * n;
    const double vt_len = vt.norm();
    Vec3 J = jn * n;
    if (vt_len > 0.0) J -= std::min(def.friction * jn, vt_len / inv_m) * (vt / vt_len);
    // Apply to the float particle velocity, then take J from what the rounding actually left.
    Vec3 v_new;
    for (int k = 0; k < 3; ++k) {
      float& vk = vel[3 * p + std::size_t(k)];
      vk = float(double(vk) + J[k] / m_p);
      v_new[k] = vk;
    }
    J = m_p * (v_new - v1);
    for (int k = 0; k < 3; ++k) scratch.impulse[ids[k]] -= w[k] * J;
    // Rest of the step at the new relative velocity (its normal part is >= 0: moving away).
    const Vec3 rel_new = v_new - v_tri;
    const Vec3 end = best.point + (1.0 - best.s) * dt * (rel_new - std::min(0.0, rel_new.dot(n)) * n);
    for (int k = 0; k < 3; ++k) pos[3 * p + std::size_t(k)] = float(end[k]);
    ++contacts;
  }
  if (contacts > 0) cloth.apply_impulses(scratch.impulse);
  return contacts;
}

}  // namespace simreel::sim::detail
