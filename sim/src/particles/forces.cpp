// Force evaluation (Coutinho §3.3): gravity, viscous drag, damped springs (eq. 3.6), fields with
// drop-off, attractor springs (§3.3.5), and the validation of force definitions. Pair forces
// over a cut-off grid (§3.3.4) are in pair_forces.cpp, the curl noise in noise.cpp.
#include "particles/forces.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/vector_clones.hpp"
#include "particles/row_lanes.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/ranges.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace simreel::sim::detail {

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
    case FieldKind::uniform: {
      const Vec3 a = w * (rotation * (def.acceleration + def.force / m));
      if (def.wind == Vec3::Zero()) return a;
      return a + (w * def.drag / m) * (rotation * def.wind - v);
    }
    case FieldKind::blast:
      return Vec3::Zero();  // an impulse, not an acceleration (stage_integrate.cpp, body_coupling.cpp)
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
    case FieldKind::curl_noise:  // as add_curl_block(), here one particle
      return (w * def.drag / m) * (air_velocity(x, t) - v);
  }
  return Vec3::Zero();
}

// ---------------------------------------------------------------------------------------------
// Whole-system evaluation

namespace {

constexpr std::size_t kNoiseBlock = Dynamics::kBlock;  ///< particles per batch of curl-noise samples

/// Noise coordinates of len particles (rows of x): p = frequency (R^T (x - c) - scroll t), with
/// r = R^T row-major (r[3 i + j] = R(j, i)) and o = scroll t.
SIMREEL_VECTOR_CLONES
void noise_coordinates(std::size_t len, const double* __restrict x, const double* r,
                       const double* c, const double* o, double frequency, double* __restrict px,
                       double* __restrict py, double* __restrict pz) {
  for (std::size_t k = 0; k < len; ++k) {
    const double d0 = x[3 * k] - c[0], d1 = x[3 * k + 1] - c[1], d2 = x[3 * k + 2] - c[2];
    px[k] = frequency * (r[0] * d0 + r[1] * d1 + r[2] * d2 - o[0]);
    py[k] = frequency * (r[3] * d0 + r[4] * d1 + r[5] * d2 - o[1]);
    pz[k] = frequency * (r[6] * d0 + r[7] * d1 + r[8] * d2 - o[2]);
  }
}

/// Adds curl-noise field f's acceleration (FieldState::acceleration()) to a for the len <=
/// kNoiseBlock particles whose rows x, v, mass and a point at, the curl of each particle taken in
/// one vectorised batch (GradientNoise::curl).
void add_curl_block(const FieldState& f, std::size_t len, const double* x, const double* v,
                    const double* mass, double t, double* a) {
  alignas(64) double px[kNoiseBlock], py[kNoiseBlock], pz[kNoiseBlock];
  alignas(64) double ux[kNoiseBlock], uy[kNoiseBlock], uz[kNoiseBlock];
  alignas(64) double w[kNoiseBlock];
  const ForceFieldDef& d = f.def;
  double r[9], q[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      r[3 * i + j] = f.rotation(j, i);
      q[3 * i + j] = f.rotation(i, j);
    }
  const Vec3 o = d.scroll * t;
  noise_coordinates(len, x, r, f.centre.data(), o.data(), d.frequency, px, py, pz);
  f.noise.curl(len, px, py, pz, ux, uy, uz);
  if (d.shape == RegionShape::everywhere)
    std::fill(w, w + len, 1.0);
  else
    for (std::size_t k = 0; k < len; ++k) w[k] = f.weight(Vec3(x[3 * k], x[3 * k + 1], x[3 * k + 2]));
  add_noise_drag_rows(len, w, ux, uy, uz, q, d.amplitude, d.drag, mass, v, a);
}

}  // namespace

void Dynamics::pose_fields(double t) {
  for (FieldState* f : fields) f->pose_at(t);
}

void Dynamics::eval_block(double t, std::size_t len, const double* x, const double* v,
                          const double* mass, double* a, bool with_drag) const {
  // Gravity and drag, then each field in order, the curl-noise ones batched; per particle the
  // same sums in the same order as eval()'s particle loop.
  const double g0 = gravity.x(), g1 = gravity.y(), g2 = gravity.z();
  for (std::size_t i = 0; i < len; ++i) {
    const double c = with_drag ? drag_at(v + 3 * i) / mass[i] : 0.0;
    a[3 * i] = g0 - c * v[3 * i];
    a[3 * i + 1] = g1 - c * v[3 * i + 1];
    a[3 * i + 2] = g2 - c * v[3 * i + 2];
  }
  for (const FieldState* f : fields) {
    if (f->def.kind == FieldKind::curl_noise) {
      add_curl_block(*f, len, x, v, mass, t, a);
      continue;
    }
    for (std::size_t i = 0; i < len; ++i) {
      const Vec3 af = f->acceleration(Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]),
                                      Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]), mass[i], t);
      a[3 * i] += af.x();
      a[3 * i + 1] += af.y();
      a[3 * i + 2] += af.z();
    }
  }
}

void Dynamics::eval(double t, const double* x, const double* v, double* a, bool with_drag) {
  pose_fields(t);
  const double g0 = gravity.x(), g1 = gravity.y(), g2 = gravity.z();
  const bool has_fields = !fields.empty();
  bool noise = false;
  for (const FieldState* f : fields) noise = noise || f->def.kind == FieldKind::curl_noise;
  if (noise) {
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(static) num_threads(threads) if (n >= kParallelMin)
    for (std::size_t blk = 0; blk < blocks; ++blk) {
      const std::size_t b = blk * kBlock, e = std::min(n, b + kBlock);
      eval_block(t, e - b, x + 3 * b, v + 3 * b, mass + b, a + 3 * b, with_drag);
    }
  } else {
#pragma omp parallel for schedule(static) num_threads(threads) if (n >= kParallelMin)
  for (std::size_t i = 0; i < n; ++i) {
    const double c = with_drag ? drag_at(v + 3 * i) / mass[i] : 0.0;
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
    // stored as floats: beyond these they would be infinite or zero
    if (!(q.mass >= ranges::kParticleMassMin && q.mass <= ranges::kParticleFloatMax))
      bad(f + "mass", "in [1e-12, 3e38]", q.mass);
    if (!(q.radius >= ranges::kParticleRadiusMin && q.radius <= ranges::kParticleFloatMax))
      bad(f + "radius", "in [1e-6, 3e38]", q.radius);
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

Vec3 FieldState::air_velocity(const Vec3& x, double t) const {
  switch (def.kind) {
    case FieldKind::uniform:
      return rotation * def.wind;
    case FieldKind::curl_noise: {
      const Vec3 p = def.frequency * (rotation.transpose() * (x - centre) - def.scroll * t);
      return def.amplitude * (rotation * curl_noise(noise, p));
    }
    default:
      return Vec3::Zero();
  }
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
  check_vec(p + "wind", def.wind);
  if (def.kind == FieldKind::uniform) require_in(def.drag, ranges::kFieldDrag, p + "drag");
  if (def.kind == FieldKind::blast) {
    require_in(def.impulse, ranges::kFieldImpulse, p + "impulse");
    require_in(def.time, ranges::kFieldTime, p + "time");
  }
}

void validate(const AttractorSpringDef& def) {
  require_in(def.stiffness, ranges::kAttractorStiffness, "AttractorSpringDef.stiffness");
  require_in(def.damping, ranges::kAttractorDamping, "AttractorSpringDef.damping");
  check_vec("AttractorSpringDef.anchor", def.anchor);
}

}  // namespace simreel::sim::detail
