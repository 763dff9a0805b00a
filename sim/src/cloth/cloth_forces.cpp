// Cloth forces (Coutinho §3.9.2): spring forces of the three families with their Jacobian
// blocks for the implicit solver, gravity, damping, gusty wind and aerodynamic drag and lift.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/cloth_state.hpp"
#include "cloth/gust_noise.hpp"

namespace simreel::sim {

using detail::value_noise;

Vec3 Cloth::State::wind(const Vec3& p, double t) const {
  const WindDef& w = def.wind;
  if (w.gust_amplitude == 0.0) return w.velocity;
  const double speed = w.velocity.norm();
  // The gust pattern travels with the mean wind: what reaches p at t left the origin at t - s/|w|.
  const double tau = w.gust_frequency * (speed > 0.0 ? t - p.dot(w.velocity) / (speed * speed) : t);
  return w.velocity + w.gust_amplitude * Vec3(value_noise(noise_key ^ 1, tau),
                                               value_noise(noise_key ^ 2, tau),
                                               value_noise(noise_key ^ 3, tau) / 3.0);
}

void Cloth::State::forces(double t) {
  const ClothTopology& T = *topo;
  const std::size_t ns = T.spring_count();
  const std::uint32_t* __restrict sa = T.spring_a.data();
  const std::uint32_t* __restrict sb = T.spring_b.data();
  double* __restrict len = spring_length.data();
  Vec3* __restrict F = spring_work.data();
  const int th = threads;
  const bool par = parallel();
  // Each spring's force on its end a, then each vertex gathers its springs in spring order: the
  // additions of a scatter over the springs in the same order, so the same bits at any thread
  // count.
#pragma omp parallel for schedule(static) num_threads(th) if (par)
  for (std::size_t s = 0; s < ns; ++s) {
    const std::uint32_t a = sa[s], b = sb[s];
    const Vec3 d = x[b] - x[a];
    const double l = d.norm();
    len[s] = l;  // reused by the implicit step's Jacobian (x has not moved since)
    if (!(l > 0.0)) continue;
    const Vec3 u = d * (1.0 / l);
    spring_dir[s] = u;
    F[s] = (ks[s] * (l - T.rest_length[s]) + kds[s] * (v[b] - v[a]).dot(u)) * u;
  }
  const std::uint32_t* __restrict adj_start = T.adj_start.data();
  const std::uint32_t* __restrict adj_spring = T.adj_spring.data();
#pragma omp parallel for schedule(static) num_threads(th) if (par)
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 fi = vertex_mass * (def.gravity - def.damping * v[i]);
    for (std::uint32_t k = adj_start[i]; k < adj_start[i + 1]; ++k) {
      const std::uint32_t s = adj_spring[k];
      if (!(len[s] > 0.0)) continue;
      if (sa[s] == i) fi += F[s];
      else fi -= F[s];
    }
    f[i] = fi;
  }
  const AeroDef& ae = def.aero;
  const bool jac = def.integrator == ClothIntegrator::implicit_euler;
  if (aero_active && jac) std::fill(aero_damping.begin(), aero_damping.end(), Sym3{});
  if (aero_active) {
    // Reciprocals instead of the 17 divisions per triangle the plain formulas take (this loop
    // was a tenth of the 64 x 64 peer scene's time).
    constexpr double kThird = 1.0 / 3.0;
    for (std::size_t k = 0; k + 2 < T.triangles.size(); k += 3) {
      const std::uint32_t i0 = T.triangles[k], i1 = T.triangles[k + 1], i2 = T.triangles[k + 2];
      const Vec3 c = (x[i0] + x[i1] + x[i2]) * kThird;
      const Vec3 u = wind(c, t) - (v[i0] + v[i1] + v[i2]) * kThird;
      const double u2 = u.squaredNorm();
      Vec3 nrm = (x[i1] - x[i0]).cross(x[i2] - x[i0]);
      const double twice_area = nrm.norm();
      if (!(u2 > 0.0) || !(twice_area > 0.0)) continue;
      nrm *= 1.0 / twice_area;
      const double speed = std::sqrt(u2), inv_speed = 1.0 / speed;
      const Vec3 u_hat = u * inv_speed;
      double cos_t = nrm.dot(u_hat);
      if (cos_t < 0.0) {  // turn the normal to face the wind
        nrm = -nrm;
        cos_t = -cos_t;
      }
      const double q = 0.5 * ae.air_density * u2 * 0.5 * twice_area;  // ½ ρ |u|² A
      Vec3 F = q * ae.drag_coefficient * cos_t * nrm;
      const Vec3 l = nrm - cos_t * u_hat;
      if (l.squaredNorm() > 1e-24) F += q * ae.lift_coefficient * cos_t * l;  // |l| = sin θ
      F *= kThird;
      f[i0] += F;
      f[i1] += F;
      f[i2] += F;
      if (jac) {
        // The pressure term c |u| (n·u) n has ∂/∂u = c (|u| nnᵀ + cos θ n uᵀ); its symmetric
        // bound c |u| (1 + cos θ) nnᵀ, lumped on each vertex as if it carried the triangle, keeps
        // light cloth in a gale stable at the frame step (treated explicitly, h ρ C_d |u| A / m
        // reaches ~3 for a 0.3 kg flag at 30 m/s: beyond forward Euler's limit of 2).
        const Sym3 D =
            Sym3::outer(nrm, q * ae.drag_coefficient * inv_speed * (1.0 + cos_t) * kThird);
        aero_damping[i0] += D;
        aero_damping[i1] += D;
        aero_damping[i2] += D;
      }
    }
  }
}

}  // namespace simreel::sim
