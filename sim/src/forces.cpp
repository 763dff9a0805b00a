// Force evaluation (Coutinho §3.3): gravity, viscous drag, damped springs (eq. 3.6), fields with
// drop-off, pair forces over a cut-off grid (§3.3.4), attractor springs (§3.3.5), curl noise
// (Bridson et al. 2007).
#include "forces.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/ranges.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Gradient noise

GradientNoise::GradientNoise(std::uint64_t seed) {
  Rng rng(seed, 0xC0FFEE);
  for (int i = 0; i < 256; ++i) perm_[i] = std::uint8_t(i);
  for (int i = 255; i > 0; --i) {  // Fisher–Yates with the project's generator
    const int j = int(rng.next_u64() % std::uint64_t(i + 1));
    std::swap(perm_[i], perm_[j]);
  }
  for (int i = 0; i < 256; ++i) perm_[256 + i] = perm_[i];
}

namespace {

/// The 12 edge directions of a cube (Perlin 2002), picked by the low bits of the hash.
Vec3 gradient_of(int h) {
  static const double g[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                  {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                  {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                  {1, 1, 0}, {-1, 1, 0}, {0, -1, 1}, {0, -1, -1}};
  const double* r = g[h & 15];
  return {r[0], r[1], r[2]};
}

}  // namespace

double GradientNoise::sample(const Vec3& p, Vec3& grad) const {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int ix = int(std::int64_t(fx) & 255), iy = int(std::int64_t(fy) & 255),
            iz = int(std::int64_t(fz) & 255);
  const Vec3 f(p.x() - fx, p.y() - fy, p.z() - fz);
  // Quintic fade 6t^5 - 15t^4 + 10t^3 and its derivative: C2, so the curl is C1.
  Vec3 u, du;
  for (int k = 0; k < 3; ++k) {
    const double t = f[k];
    u[k] = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    du[k] = 30.0 * t * t * (t * (t - 2.0) + 1.0);
  }
  auto corner = [&](int cx, int cy, int cz, double& value) {
    const int h = perm_[perm_[perm_[ix + cx] + iy + cy] + iz + cz];
    const Vec3 g = gradient_of(h);
    value = g.dot(f - Vec3(cx, cy, cz));
    return g;
  };
  double va, vb, vc, vd, ve, vf, vg, vh;
  const Vec3 ga = corner(0, 0, 0, va), gb = corner(1, 0, 0, vb), gc = corner(0, 1, 0, vc),
             gd = corner(1, 1, 0, vd), ge = corner(0, 0, 1, ve), gf = corner(1, 0, 1, vf),
             gg = corner(0, 1, 1, vg), gh = corner(1, 1, 1, vh);
  // Trilinear blend of the corner ramps and its exact derivative (Quilez, "gradient noise
  // derivatives"): value = k0 + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw.
  const double k1 = vb - va, k2 = vc - va, k3 = ve - va, k4 = va - vb - vc + vd,
               k5 = va - vc - ve + vg, k6 = va - vb - ve + vf,
               k7 = -va + vb + vc - vd + ve - vf - vg + vh;
  const double x = u.x(), y = u.y(), z = u.z();
  const double value = va + k1 * x + k2 * y + k3 * z + k4 * x * y + k5 * y * z + k6 * z * x +
                       k7 * x * y * z;
  // The same trilinear blend of the corner gradients, written as nested lerps (cheaper than
  // the expanded form and algebraically equal).
  const Vec3 gx00 = ga + x * (gb - ga), gx10 = gc + x * (gd - gc);
  const Vec3 gx01 = ge + x * (gf - ge), gx11 = gg + x * (gh - gg);
  const Vec3 gy0 = gx00 + y * (gx10 - gx00), gy1 = gx01 + y * (gx11 - gx01);
  grad = gy0 + z * (gy1 - gy0);
  grad.x() += du.x() * (k1 + k4 * y + k6 * z + k7 * y * z);
  grad.y() += du.y() * (k2 + k4 * x + k5 * z + k7 * x * z);
  grad.z() += du.z() * (k3 + k5 * y + k6 * x + k7 * x * y);
  return value;
}

Vec3 curl_noise(const GradientNoise& noise, const Vec3& p) {
  // Offsets far apart relative to the noise's correlation length (1) decorrelate the components.
  static const Vec3 o1(31.416, -47.853, 12.793), o2(-93.989, 26.433, 83.279);
  Vec3 g1, g2, g3;
  noise.sample(p, g1);
  noise.sample(p + o1, g2);
  noise.sample(p + o2, g3);
  // curl (ψ1, ψ2, ψ3) = (∂ψ3/∂y - ∂ψ2/∂z, ∂ψ1/∂z - ∂ψ3/∂x, ∂ψ2/∂x - ∂ψ1/∂y)
  return {g3.y() - g2.z(), g1.z() - g3.x(), g2.x() - g1.y()};
}

// ---------------------------------------------------------------------------------------------
// Fields

void FieldState::pose_at(double t) {
  const Transform tr = def.path.empty() ? def.transform : def.path.sample(t);
  centre = tr.translation;
  rotation = tr.rotation.toRotationMatrix();
}

double FieldState::weight(const Vec3& x) const {
  double d = 0.0;
  switch (def.shape) {
    case RegionShape::everywhere:
      return 1.0;
    case RegionShape::sphere:
      d = (x - centre).norm() / def.radius;
      break;
    case RegionShape::box: {
      const Vec3 local = rotation.transpose() * (x - centre);
      d = std::max({std::abs(local.x()) / def.half_extents.x(),
                    std::abs(local.y()) / def.half_extents.y(),
                    std::abs(local.z()) / def.half_extents.z()});
      break;
    }
  }
  if (d > 1.0) return 0.0;
  switch (def.falloff) {
    case Falloff::none: return 1.0;
    case Falloff::linear: return 1.0 - d;
    case Falloff::quadratic: return (1.0 - d) * (1.0 - d);
  }
  return 1.0;
}

Vec3 FieldState::acceleration(const Vec3& x, const Vec3& v, double m, double t) const {
  const double w = weight(x);
  if (w == 0.0) return Vec3::Zero();
  switch (def.kind) {
    case FieldKind::uniform:
      return w * (rotation * (def.acceleration + def.force / m));
    case FieldKind::attractor: {
      const Vec3 d = centre - x;
      const double r = d.norm();
      return r > 1e-12 ? Vec3(w * def.strength / r * d) : Vec3::Zero();
    }
    case FieldKind::vortex: {
      const Vec3 axis = rotation * def.axis;
      Vec3 rho = x - centre;
      rho -= axis * axis.dot(rho);
      const double r = rho.norm();
      if (!(r > 1e-12)) return Vec3::Zero();
      const Vec3 rhat = rho / r;
      return w * (def.strength * axis.cross(rhat) - def.inward_strength * rhat);
    }
    case FieldKind::curl_noise: {
      const Vec3 p = def.frequency * (rotation.transpose() * (x - centre) - def.scroll * t);
      const Vec3 u = def.amplitude * (rotation * curl_noise(noise, p));
      return (w * def.drag / m) * (u - v);
    }
  }
  return Vec3::Zero();
}

// ---------------------------------------------------------------------------------------------
// Pair forces over a grid of cut-off cells (§3.3.4)

namespace {

constexpr std::int64_t kCellBias = 1 << 20;  // 21 bits per axis: +-1M cells

std::uint64_t cell_key(std::int64_t cx, std::int64_t cy, std::int64_t cz) {
  auto c = [](std::int64_t v) {
    return std::uint64_t(std::clamp<std::int64_t>(v + kCellBias, 0, 2 * kCellBias - 1));
  };
  return (c(cx) << 42) | (c(cy) << 21) | c(cz);
}

}  // namespace

void Dynamics::add_pair_forces(const double* x, double* a) {
  const double cut = pair.cutoff, cut2 = cut * cut, eps2 = pair.softening * pair.softening;
  const double inv = 1.0 / cut;
  // Build: each particle's cell key, sorted with its index (a total order, so the layout is
  // independent of the thread count), then a hash of occupied cells -> run in the sorted array.
  cell_key_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t k = cell_key(std::int64_t(std::floor(x[3 * i] * inv)),
                                     std::int64_t(std::floor(x[3 * i + 1] * inv)),
                                     std::int64_t(std::floor(x[3 * i + 2] * inv)));
    cell_key_[i] = k;
  }
  std::vector<std::uint64_t>& keys = cell_key_;
  std::vector<std::uint32_t>& order = order_;
  order.resize(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
    return keys[p] != keys[q] ? keys[p] < keys[q] : p < q;
  });
  // Occupied cells in key order: key and first particle of each run.
  cell_keys_.clear();
  cell_start_.clear();
  for (std::size_t s = 0; s < n; ++s)
    if (s == 0 || keys[order[s]] != keys[order[s - 1]]) {
      cell_keys_.push_back(keys[order[s]]);
      cell_start_.push_back(std::uint32_t(s));
    }
  cell_start_.push_back(std::uint32_t(n));
  const double G = pair.gravitational_G, K = pair.coulomb_K;
  // Copy (x, y, z, q, m) into cell order: a neighbour cell's particles are then contiguous and
  // the gather reads memory in order instead of at random.
  sorted_.resize(5 * n);
  for (std::size_t s = 0; s < n; ++s) {
    const std::size_t i = order[s];
    double* o = &sorted_[5 * s];
    o[0] = x[3 * i];
    o[1] = x[3 * i + 1];
    o[2] = x[3 * i + 2];
    o[3] = charge ? charge[i] : 0.0;
    o[4] = mass[i];
  }
  const double* xs = sorted_.data();
  const std::size_t cells = cell_keys_.size();
  const std::uint64_t* ck = cell_keys_.data();
  const std::uint32_t* cs = cell_start_.data();
  // Gather, one occupied cell at a time. Keys order cells by (x, y, z), so the three cells of a
  // neighbour column (dx, dy, dz = -1..1) are one contiguous run of particles, and as the cells
  // are visited in key order each column's start only moves forward: nine cursors replace 27
  // lookups. Particle i sums its neighbours in a fixed order, whichever thread computes it.
  const int parts = n >= kParallelMin / 8 && threads > 1 ? threads : 1;
#pragma omp parallel num_threads(parts) if (parts > 1)
  {
#ifdef _OPENMP
    const std::size_t t = std::size_t(omp_get_thread_num()), nt = std::size_t(omp_get_num_threads());
#else
    const std::size_t t = 0, nt = 1;
#endif
    const std::size_t c_begin = cells * t / nt, c_end = cells * (t + 1) / nt;
    std::size_t cursor[9];
    for (std::size_t c = c_begin; c < c_end; ++c) {
      const double* o0 = xs + 5 * std::size_t(cs[c]);
      const std::int64_t cx = std::int64_t(std::floor(o0[0] * inv)),
                         cy = std::int64_t(std::floor(o0[1] * inv)),
                         cz = std::int64_t(std::floor(o0[2] * inv));
      std::uint32_t run_b[9], run_e[9];
      for (int col = 0; col < 9; ++col) {
        const std::int64_t dx = col / 3 - 1, dy = col % 3 - 1;
        const std::uint64_t lo = cell_key(cx + dx, cy + dy, cz - 1);
        const std::uint64_t hi = cell_key(cx + dx, cy + dy, cz + 1);
        std::size_t& cur = cursor[col];
        if (c == c_begin)
          cur = std::size_t(std::lower_bound(ck, ck + cells, lo) - ck);
        else
          while (cur < cells && ck[cur] < lo) ++cur;
        std::size_t end = cur;
        while (end < cells && ck[end] <= hi) ++end;
        run_b[col] = cs[cur];
        run_e[col] = cs[end];
      }
      for (std::uint32_t si = cs[c]; si < cs[c + 1]; ++si) {
        const double xi = xs[5 * si], yi = xs[5 * si + 1], zi = xs[5 * si + 2];
        const double qi = xs[5 * si + 3], mi = xs[5 * si + 4];
        double ax = 0, ay = 0, az = 0;
        for (int r = 0; r < 9; ++r)
          for (std::uint32_t s = run_b[r]; s < run_e[r]; ++s) {
            if (s == si) continue;
            const double* o = xs + 5 * std::size_t(s);
            const double ddx = xi - o[0], ddy = yi - o[1], ddz = zi - o[2];
            const double r2 = ddx * ddx + ddy * ddy + ddz * ddz;
            if (!(r2 < cut2)) continue;
            const double s2 = r2 + eps2;
            const double coef = (K * qi * o[3] - G * mi * o[4]) / (s2 * std::sqrt(s2));
            ax += coef * ddx;
            ay += coef * ddy;
            az += coef * ddz;
          }
        const std::size_t i = order[si];
        a[3 * i] += ax / mi;
        a[3 * i + 1] += ay / mi;
        a[3 * i + 2] += az / mi;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Whole-system evaluation

void Dynamics::eval(double t, const double* x, const double* v, double* a, bool with_drag) {
  for (FieldState* f : fields) f->pose_at(t);
  const double g0 = gravity.x(), g1 = gravity.y(), g2 = gravity.z();
  const bool has_fields = !fields.empty();
#pragma omp parallel for schedule(static) num_threads(threads) if (n >= kParallelMin)
  for (std::size_t i = 0; i < n; ++i) {
    const double c = with_drag ? drag / mass[i] : 0.0;
    double ax = g0 - c * v[3 * i], ay = g1 - c * v[3 * i + 1], az = g2 - c * v[3 * i + 2];
    if (has_fields) {
      const Vec3 xi(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
      const Vec3 vi(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
      for (const FieldState* f : fields) {
        const Vec3 af = f->acceleration(xi, vi, mass[i], t);
        ax += af.x();
        ay += af.y();
        az += af.z();
      }
    }
    a[3 * i] = ax;
    a[3 * i + 1] = ay;
    a[3 * i + 2] = az;
  }
  if (pair.enabled() && n > 1) add_pair_forces(x, a);
  // Springs scatter into both ends: serial, in definition order (few, and deterministic).
  for (const Spring& s : springs) {
    const Vec3 l(x[3 * s.i] - x[3 * s.j], x[3 * s.i + 1] - x[3 * s.j + 1],
                 x[3 * s.i + 2] - x[3 * s.j + 2]);
    const Vec3 ldot(v[3 * s.i] - v[3 * s.j], v[3 * s.i + 1] - v[3 * s.j + 1],
                    v[3 * s.i + 2] - v[3 * s.j + 2]);
    const double len = l.norm();
    if (!(len > 1e-12)) continue;
    const Vec3 dir = l / len;
    const Vec3 f = -(s.ks * (len - s.rest) + s.kd * ldot.dot(dir)) * dir;  // on i (eq. 3.6)
    for (int k = 0; k < 3; ++k) {
      a[3 * s.i + k] += f[k] / mass[s.i];
      a[3 * s.j + k] -= f[k] / mass[s.j];
    }
  }
  for (const Pull& p : pulls) {
    const AttractorSpringDef& d = *p.def;
    const Vec3 anchor = d.path.empty() ? d.anchor : d.path.sample(t).translation;
    const Vec3 anchor_v = d.path.empty() ? Vec3::Zero() : d.path.velocity(t);
    auto pull = [&](std::size_t i) {
      for (int k = 0; k < 3; ++k)
        a[3 * i + k] += (-d.stiffness * (x[3 * i + k] - anchor[k]) -
                         d.damping * (v[3 * i + k] - anchor_v[k])) / mass[i];
    };
    if (p.all)
      for (std::size_t i = 0; i < n; ++i) pull(i);
    else
      for (std::uint32_t i : p.index) pull(i);
  }
}

}  // namespace simreel::sim::detail

// ---------------------------------------------------------------------------------------------
// Validation

namespace simreel::sim::detail {

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& expected, double found) {
  std::ostringstream m;
  m << field << " must be " << expected << " (got " << found << ")";
  throw std::invalid_argument(m.str());
}

void check_nonneg(const std::string& field, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(field, ">= 0 and finite", v);
}

void check_pos(const std::string& field, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(field, "> 0 and finite", v);
}

void check_vec(const std::string& field, const Vec3& v) {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(v[k])) bad(field, "finite", v[k]);
}

}  // namespace

void validate_forces(const ParticleSystemDef& def) {
  const std::string p = "ParticleSystemDef(" + def.name + ").";
  switch (def.integrator) {
    case Integrator::semi_implicit_euler: case Integrator::rk4: case Integrator::explicit_euler:
    case Integrator::rk2: case Integrator::implicit_euler: case Integrator::adaptive:
      break;
    default:
      bad(p + "integrator", "one of the Integrator values", double(int(def.integrator)));
  }
  require_in(def.tolerance, ranges::kSystemTolerance, p + "tolerance");
  if (def.initial_particles.size() > def.emitter.max_particles)
    bad(p + "initial_particles.size()", "<= emitter.max_particles",
        double(def.initial_particles.size()));
  for (std::size_t i = 0; i < def.initial_particles.size(); ++i) {
    const InitialParticle& q = def.initial_particles[i];
    const std::string f = p + "initial_particles[" + std::to_string(i) + "].";
    check_vec(f + "position", q.position);
    check_vec(f + "velocity", q.velocity);
    check_pos(f + "mass", q.mass);
    check_pos(f + "radius", q.radius);
    if (!std::isfinite(q.charge)) bad(f + "charge", "finite", q.charge);
  }
  for (std::size_t i = 0; i < def.springs.size(); ++i) {
    const SpringDef& s = def.springs[i];
    const std::string f = p + "springs[" + std::to_string(i) + "].";
    const double n = double(def.initial_particles.size());
    if (s.a >= def.initial_particles.size()) bad(f + "a", "an index < initial_particles.size() = " + std::to_string(def.initial_particles.size()), double(s.a));
    if (s.b >= def.initial_particles.size() || s.b == s.a)
      bad(f + "b", "an index < " + std::to_string(std::size_t(n)) + " other than a", double(s.b));
    require_in(s.stiffness, ranges::kSpringStiffness, f + "stiffness");
    require_in(s.damping, ranges::kSpringDamping, f + "damping");
    if (!std::isfinite(s.rest_length)) bad(f + "rest_length", "finite (< 0 = initial distance)", s.rest_length);
  }
  require_in(def.pair_forces.gravitational_G, ranges::kPairG, p + "pair_forces.gravitational_G");
  require_in(def.pair_forces.coulomb_K, ranges::kPairK, p + "pair_forces.coulomb_K");
  require_in(def.pair_forces.softening, ranges::kPairSoftening, p + "pair_forces.softening");
  if (def.pair_forces.enabled()) require_in(def.pair_forces.cutoff, ranges::kPairCutoff, p + "pair_forces.cutoff");
  if (!std::isfinite(def.charge.mean)) bad(p + "charge.mean", "finite", def.charge.mean);
  check_nonneg(p + "charge.deviation", def.charge.deviation);
}

void validate(const ForceFieldDef& def) {
  const std::string p = "ForceFieldDef.";
  if (def.shape == RegionShape::sphere) require_in(def.radius, ranges::kFieldRadius, p + "radius");
  if (def.shape == RegionShape::box)
    for (int k = 0; k < 3; ++k) require_in(def.half_extents[k], ranges::kFieldHalfExtent, p + "half_extents");
  check_vec(p + "acceleration", def.acceleration);
  check_vec(p + "force", def.force);
  check_vec(p + "scroll", def.scroll);
  check_vec(p + "transform.translation", def.transform.translation);
  if (!std::isfinite(def.strength)) bad(p + "strength", "finite", def.strength);
  if (!std::isfinite(def.inward_strength)) bad(p + "inward_strength", "finite", def.inward_strength);
  check_vec(p + "axis", def.axis);
  if (def.kind == FieldKind::vortex && !(def.axis.norm() > 1e-12))
    bad(p + "axis", "a non-zero vector", def.axis.norm());
  if (def.kind == FieldKind::curl_noise) {
    require_in(def.frequency, ranges::kFieldFrequency, p + "frequency");
    require_in(def.amplitude, ranges::kFieldAmplitude, p + "amplitude");
    require_in(def.drag, ranges::kFieldDrag, p + "drag");
  }
}

void validate(const AttractorSpringDef& def) {
  require_in(def.stiffness, ranges::kAttractorStiffness, "AttractorSpringDef.stiffness");
  require_in(def.damping, ranges::kAttractorDamping, "AttractorSpringDef.damping");
  check_vec("AttractorSpringDef.anchor", def.anchor);
}

}  // namespace simreel::sim::detail
