// Cloth forces (Coutinho §3.9.2): spring forces of the three families with their Jacobian
// blocks for the implicit solver, gravity, damping, gusty wind and aerodynamic drag and lift.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/cloth_state.hpp"
#include "cloth/gust_noise.hpp"
#include "cloth/aero.hpp"

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
  const int th = threads;
  const bool par = parallel();
  const std::size_t st = stencil.stride();
  double* xs = soa.data() + stencil.pad();
  double* vs = xs + 3 * st;
  double* fs = vs + 3 * st;
  if (!stencil.empty() || aero_active)
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < 3; ++k) {
        xs[k * st + i] = x[i][Eigen::Index(k)];
        vs[k * st + i] = v[i][Eigen::Index(k)];
      }
  if (!stencil.empty()) {
    // A grid cloth: the springs by offset class in structures of arrays (spring_stencil.hpp).
    stencil.forces(xs, vs, vertex_mass, def.gravity, def.damping, fs, par ? th : 1);
  } else {
    const std::size_t ns = T.spring_count();
    const std::uint32_t* __restrict sa = T.spring_a.data();
    const std::uint32_t* __restrict sb = T.spring_b.data();
    double* __restrict len = spring_length.data();
    Vec3* __restrict F = spring_work.data();
    // Each spring's force on its end a, then each vertex gathers its springs in spring order:
    // the additions of a scatter over the springs in the same order, so the same bits at any
    // thread count.
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
  }
  const bool jac = def.integrator == ClothIntegrator::implicit_euler;
  const detail::AeroCoefficients coef{def.aero.air_density, def.aero.drag_coefficient,
                                      def.aero.lift_coefficient};
  const bool gusts = def.wind.gust_amplitude != 0.0;
  constexpr double kThird = 1.0 / 3.0;
  auto centroid = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return Vec3((x[a] + x[b] + x[c]) * kThird);
  };
  if (aero_grid) {
    // Aerodynamics by grid cell, vectorised (aero.hpp), summed per vertex into fs.
    double* wind_at = aero_work.data() + stencil.pad();  // 2 triangles x 3 arrays
    double* cells = wind_at + 6 * st;
    double* work = cells + st;  // 2 x 9 arrays
    double* Dg = work + 18 * st;  // 6 arrays
    const auto C = std::uint32_t(T.columns);
    for (std::size_t a = 0; a < n; ++a) {
      Vec3 w0 = def.wind.velocity, w1 = w0;
      if (gusts && cells[a] > 0.0) {
        const auto i = std::uint32_t(a);
        w0 = wind(centroid(i, i + C, i + C + 1), t);
        w1 = wind(centroid(i, i + C + 1, i + 1), t);
      }
      for (std::size_t k = 0; k < 3; ++k) {
        wind_at[k * st + a] = w0[Eigen::Index(k)];
        wind_at[(3 + k) * st + a] = w1[Eigen::Index(k)];
      }
    }
    detail::aero_grid(T.rows, T.columns, xs, vs, std::ptrdiff_t(st), wind_at, cells, coef, work,
                      fs, Dg, par ? th : 1);
    if (jac)
      for (std::size_t i = 0; i < n; ++i)
        aero_damping[i] = Sym3::load(Dg + i, st);
  }
  if (!stencil.empty())
    for (std::size_t i = 0; i < n; ++i) f[i] = Vec3(fs[i], fs[st + i], fs[2 * st + i]);
  if (!aero_active || aero_grid) return;
  // Aerodynamics by triangle (aero.hpp), added to the vertices in triangle order.
  const std::size_t nt = T.triangles.size() / 3;
  double* gw = aero_work.data();  // the wind at each triangle's centroid (3 arrays)
  double* out = gw + 3 * nt;      // F / 3 (3 arrays), then the damping block (6 arrays)
  for (std::size_t k = 0; k < nt; ++k) {
    const std::uint32_t* tri = &T.triangles[3 * k];
    const Vec3 w = gusts ? wind(centroid(tri[0], tri[1], tri[2]), t) : def.wind.velocity;
    gw[k] = w.x();
    gw[nt + k] = w.y();
    gw[2 * nt + k] = w.z();
  }
  detail::aero_triangles(nt, T.triangles.data(), xs, vs, std::ptrdiff_t(st), gw, coef, out);
  if (jac) std::fill(aero_damping.begin(), aero_damping.end(), Sym3{});
  for (std::size_t k = 0; k < nt; ++k) {
    const Vec3 F(out[k], out[nt + k], out[2 * nt + k]);
    const Sym3 D = Sym3::load(out + 3 * nt + k, nt);
    for (std::size_t e = 0; e < 3; ++e) {
      const std::uint32_t i = T.triangles[3 * k + e];
      f[i] += F;
      if (jac) aero_damping[i] += D;
    }
  }
}

}  // namespace simreel::sim
