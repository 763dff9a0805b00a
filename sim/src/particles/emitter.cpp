// Emitters (Coutinho §3.8) and the validation of particle-system definitions.
#include "particles/emitter.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/validate.hpp"

namespace simreel::sim::detail {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMinMass = ranges::kParticleMassMin;  // (kg) floor of a mass draw
constexpr double kMinRadius = ranges::kParticleRadiusMin;  // (m) floor of a radius draw

/// Number of births up to and including time t, given x = rate * (t - start): birth j (from 0)
/// is at start + (j + 1) / rate, so the count is floor(x) — the same for any cut of [start, t]
/// into frames and steps. The relative epsilon keeps a birth that falls on t (x an integer but
/// computed as 59.999999999) in the step that ends there, whatever the fps.
std::uint64_t births_until(double x) {
  if (!(x > 0.0)) return 0;
  return std::uint64_t(std::floor(x + 1e-9 * std::max(1.0, x)));
}

double draw(Rng& rng, const Distribution& d) {
  if (d.uniform) return rng.uniform(d.min, d.max);
  return std::clamp(rng.normal(d.mean, d.deviation), d.min, d.max);
}

Transform frame_at(const EmitterDef& def, double t) {
  Transform f = def.path.empty() ? def.transform : def.path.sample(t);
  f.rotation.normalize();
  return f;
}

/// Chooses k distinct cells out of n (k <= n) into `out`, in draw order.
void choose_distinct(Rng& rng, std::uint64_t n, std::size_t k, std::vector<std::uint64_t>& out,
                     std::vector<std::uint64_t>& scratch) {
  out.clear();
  if (n <= 4 * std::uint64_t(k)) {
    // Dense: partial Fisher–Yates over all cells (n is at most 4k here, so this is bounded by the
    // release size).
    scratch.resize(std::size_t(n));
    std::iota(scratch.begin(), scratch.end(), std::uint64_t{0});
    for (std::size_t i = 0; i < k; ++i) {
      const std::uint64_t j = i + std::min<std::uint64_t>(
                                      std::uint64_t(rng.uniform() * double(n - i)), n - i - 1);
      std::swap(scratch[i], scratch[std::size_t(j)]);
      out.push_back(scratch[i]);
    }
    return;
  }
  // Sparse: rejection sampling against an open-addressing set (at least 3/4 of draws succeed).
  std::size_t size = 16;
  while (size < 2 * k) size *= 2;
  constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  scratch.assign(size, kEmpty);
  while (out.size() < k) {
    const std::uint64_t c = std::min<std::uint64_t>(std::uint64_t(rng.uniform() * double(n)), n - 1);
    std::size_t slot = std::size_t((c * 0x9E3779B97F4A7C15ULL) >> 20) & (size - 1);
    while (scratch[slot] != kEmpty && scratch[slot] != c) slot = (slot + 1) & (size - 1);
    if (scratch[slot] == c) continue;
    scratch[slot] = c;
    out.push_back(c);
  }
}

/// Lays out one release on the quad (Coutinho §3.8, eq. 3.100: a square of side f_s = 2 d sqrt(n)
/// holds n particles of diameter d, i.e. cells of side 2 d). Cells of side 2 d_max (d_max the
/// largest diameter of this release) are tried first, then d_max; every particle gets its own
/// random cell and a random offset that keeps it inside that cell, so particles of one release
/// never overlap while the quad has room. When it has not, further rounds reuse the cells.
void layout_quad(const std::array<double, 2>& quad_size, EmitterState& st, ParticleStore& s,
                 std::size_t first, std::size_t n) {
  std::vector<double>& local = st.local;  // (n x 2) start points in the emitter frame (m)
  local.resize(2 * n);
  double d_max = 0.0;
  for (std::size_t i = first; i < first + n; ++i) d_max = std::max(d_max, 2.0 * double(s.radius[i]));
  const double lx = quad_size[0], ly = quad_size[1];
  auto cells_along = [](double length, double cell) {
    return std::min(std::floor(length / cell), double(1u << 30));
  };
  double cell = 2.0 * d_max;
  double nx = cells_along(lx, cell), ny = cells_along(ly, cell);
  if (nx * ny < double(n)) {
    cell = d_max;
    nx = cells_along(lx, cell);
    ny = cells_along(ly, cell);
  }
  // An axis shorter than one cell holds a single cell as wide as the quad.
  const double wx = nx >= 1.0 ? cell : lx, wy = ny >= 1.0 ? cell : ly;
  nx = std::max(nx, 1.0);
  ny = std::max(ny, 1.0);
  const std::uint64_t ncells = std::uint64_t(nx) * std::uint64_t(ny);
  const double ox = -0.5 * nx * wx, oy = -0.5 * ny * wy;

  std::size_t placed = 0;
  while (placed < n) {
    const std::size_t k = std::size_t(std::min<std::uint64_t>(ncells, n - placed));
    choose_distinct(st.rng, ncells, k, st.cells, st.scratch);
    for (std::size_t c = 0; c < k; ++c, ++placed) {
      const std::uint64_t cell_index = st.cells[c];
      const double cx = double(cell_index % std::uint64_t(nx));
      const double cy = double(cell_index / std::uint64_t(nx));
      const double r = s.radius[first + placed];
      const double ax = std::max(0.0, 0.5 * wx - r), ay = std::max(0.0, 0.5 * wy - r);
      const double jx = st.rng.uniform(-ax, ax), jy = st.rng.uniform(-ay, ay);
      local[2 * placed] = ox + (cx + 0.5) * wx + jx;
      local[2 * placed + 1] = oy + (cy + 0.5) * wy + jy;
    }
  }
}


/// Builds the cumulative triangle areas of a mesh emitter (once).
void build_mesh_cdf(const EmitterDef& def, EmitterState& st) {
  const std::size_t m = def.mesh_triangles.size() / 3;
  st.mesh_cdf.resize(m);
  double total = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    Vec3 v[3];
    for (int c = 0; c < 3; ++c) {
      const std::size_t vi = def.mesh_triangles[3 * k + std::size_t(c)];
      v[c] = Vec3(def.mesh_positions[3 * vi], def.mesh_positions[3 * vi + 1],
                  def.mesh_positions[3 * vi + 2]);
    }
    total += 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).norm();
    st.mesh_cdf[k] = total;
  }
}

Vec3 mesh_vertex(const EmitterDef& def, std::size_t tri, int corner) {
  const std::size_t vi = def.mesh_triangles[3 * tri + std::size_t(corner)];
  return {def.mesh_positions[3 * vi], def.mesh_positions[3 * vi + 1],
          def.mesh_positions[3 * vi + 2]};
}

/// Appends to `births` the birth times of this step, earliest first, at most `room` of them.
void schedule(const EmitterDef& def, EmitterState& st, double t1, std::size_t room) {
  std::vector<double>& births = st.births;
  births.clear();
  if (def.rate > 0.0) {
    const double t_hi = std::min(t1, def.stop_time);
    const std::uint64_t target = births_until(def.rate * (t_hi - def.start_time));
    if (target > st.scheduled) {
      // Only the earliest `room` can be released; the rest are dropped at the cap.
      const std::uint64_t n = std::min<std::uint64_t>(target - st.scheduled, room);
      for (std::uint64_t j = st.scheduled; j < st.scheduled + n; ++j)
        births.push_back(def.start_time + double(j + 1) / def.rate);
      st.scheduled = target;
    }
  }
  if (def.bursts.empty()) return;
  st.bursts_fired.resize(def.bursts.size(), 0);
  const double t_edge = t1 + 1e-9 * std::max(1.0, std::abs(t1));  // a burst on t1 is in this step
  const std::size_t rate_births = births.size();
  for (std::size_t b = 0; b < def.bursts.size(); ++b) {
    const Burst& burst = def.bursts[b];
    const std::uint64_t cycles =
        burst.repeat_interval > 0.0 ? (burst.cycles == 0 ? ~std::uint64_t{0} : burst.cycles) : 1;
    std::uint64_t& fired = st.bursts_fired[b];
    while (fired < cycles) {
      const double t = burst.time + double(fired) * burst.repeat_interval;
      if (!(t <= t_edge)) break;
      const std::size_t n = std::min(burst.count, room);
      births.insert(births.end(), n, std::min(t, t1));
      ++fired;
    }
  }
  if (births.size() > rate_births) std::stable_sort(births.begin(), births.end());
  if (births.size() > room) births.resize(room);
}

/// Where and when newborn k of a release starts: the emitter frame it is placed in, its age at
/// the end of the step, and a velocity added to its own draw (inherited).
struct BirthPose {
  Transform frame;
  double age = 0.0;
  bool inherit = false;  ///< add `velocity` (a plain emitter without inherited velocity adds nothing)
  Vec3 velocity = Vec3::Zero();
};

/// Draws particles [first, first + n) (already appended) from the emitter's distributions, newborn
/// k placed by pose(k) (a BirthPose).
template <class PoseOf>
void release(const EmitterDef& def, EmitterState& st, ParticleStore& s, std::size_t first,
             std::size_t n, const PoseOf& pose, std::uint64_t& next_id) {
  if (def.shape == EmitterShape::mesh && st.mesh_cdf.empty()) build_mesh_cdf(def, st);
  // Per-particle draws in a fixed order (the same seed gives the same particles): lifetime,
  // speed, spread, azimuth, mass, radius, the start point (shape draws), brightness.
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = first + k;
    const BirthPose b = pose(k);
    const double age = b.age;
    const double lifetime = std::max(0.0, draw(st.rng, def.lifetime));
    const double speed = draw(st.rng, def.start_speed);
    // A negative polar angle at azimuth phi is the positive one at phi + 180 deg, so normal
    // draws are folded rather than clamped at 0 (which would send half of them along the normal).
    const double spread_raw = def.spread_deg.uniform
                                  ? st.rng.uniform(def.spread_deg.min, def.spread_deg.max)
                                  : std::abs(st.rng.normal(def.spread_deg.mean,
                                                           def.spread_deg.deviation));
    const double spread_deg =
        std::clamp(std::clamp(spread_raw, def.spread_deg.min, def.spread_deg.max), 0.0, 180.0);
    const double azimuth = 2.0 * kPi * st.rng.uniform();
    const double mass = std::max(kMinMass, draw(st.rng, def.mass));
    const double radius = std::max(kMinRadius, draw(st.rng, def.radius));

    const double theta = spread_deg * (kPi / 180.0);
    Vec3 dir_local(std::sin(theta) * std::cos(azimuth), std::sin(theta) * std::sin(azimuth),
                   std::cos(theta));
    const Transform& f = b.frame;

    // Start point in the emitter frame (quad and cube: laid out below, per release).
    Vec3 p_local = Vec3::Zero();
    switch (def.shape) {
      case EmitterShape::disk: {
        // sqrt: uniform over the disk's area, not its radius.
        const double rho = def.disk_radius * std::sqrt(st.rng.uniform());
        const double phi = 2.0 * kPi * st.rng.uniform();
        p_local = Vec3(rho * std::cos(phi), rho * std::sin(phi), 0.0);
        break;
      }
      case EmitterShape::sphere: {
        // Archimedes: z uniform in [-1, 1] gives a point uniform over the sphere's area.
        const double z = 2.0 * st.rng.uniform() - 1.0;
        const double phi = 2.0 * kPi * st.rng.uniform();
        const double rxy = std::sqrt(std::max(0.0, 1.0 - z * z));
        const Vec3 normal(rxy * std::cos(phi), rxy * std::sin(phi), z);
        p_local = def.sphere_radius * normal;
        dir_local = Quat::FromTwoVectors(Vec3::UnitZ(), normal) * dir_local;
        break;
      }
      case EmitterShape::box:
        for (int c = 0; c < 3; ++c)
          p_local[c] = def.box_size[std::size_t(c)] * (st.rng.uniform() - 0.5);
        break;
      case EmitterShape::mesh: {
        // Area-weighted triangle, then a uniform point on it (fold the unit square's upper
        // triangle onto the lower one).
        const double total = st.mesh_cdf.back();
        const auto it =
            std::upper_bound(st.mesh_cdf.begin(), st.mesh_cdf.end(), st.rng.uniform() * total);
        const std::size_t tri =
            std::min(std::size_t(it - st.mesh_cdf.begin()), st.mesh_cdf.size() - 1);
        double r1 = st.rng.uniform(), r2 = st.rng.uniform();
        if (r1 + r2 > 1.0) {
          r1 = 1.0 - r1;
          r2 = 1.0 - r2;
        }
        const Vec3 a = mesh_vertex(def, tri, 0), b = mesh_vertex(def, tri, 1),
                   c = mesh_vertex(def, tri, 2);
        p_local = a + r1 * (b - a) + r2 * (c - a);
        const Vec3 normal = (b - a).cross(c - a).normalized();
        dir_local = Quat::FromTwoVectors(Vec3::UnitZ(), normal) * dir_local;
        break;
      }
      case EmitterShape::point:
      case EmitterShape::quad:
      case EmitterShape::cube:
        break;
    }
    Vec3 vel = f.rotation * (speed * dir_local);
    if (b.inherit) vel += b.velocity;
    const Vec3 p = f.translation + f.rotation * p_local;
    const double tint = std::clamp(st.rng.normal(1.0, def.color_deviation), 0.0, 2.0);

    s.lifetime[i] = float(lifetime);
    s.age[i] = float(age);
    s.mass[i] = float(mass);
    s.radius[i] = float(radius);
    s.base_radius[i] = float(radius);
    s.tint[i] = float(tint);
    s.id[i] = next_id++;
    for (int c = 0; c < 3; ++c) {
      s.velocity[3 * i + std::size_t(c)] = float(vel[c]);
      s.position[3 * i + std::size_t(c)] = float(p[c]);
    }
  }

  if (def.shape == EmitterShape::quad || def.shape == EmitterShape::cube) {
    // The cube emits from its top face: a cube_size square at local z = cube_size / 2.
    const bool cube = def.shape == EmitterShape::cube;
    const double z = cube ? 0.5 * def.cube_size : 0.0;
    layout_quad(cube ? std::array<double, 2>{def.cube_size, def.cube_size} : def.quad_size, st, s,
                first, n);
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = first + k;
      const Transform f = pose(k).frame;
      const Vec3 p = f.translation + f.rotation * Vec3(st.local[2 * k], st.local[2 * k + 1], z);
      for (int c = 0; c < 3; ++c) s.position[3 * i + std::size_t(c)] = float(p[c]);
    }
  }
  if (s.track_prev)
    std::copy(s.position.begin() + std::ptrdiff_t(3 * first), s.position.end(),
              s.prev_position.begin() + std::ptrdiff_t(3 * first));
}

}  // namespace

std::size_t emit(const EmitterDef& def, EmitterState& st, ParticleStore& s, double t0, double t1,
                 std::uint64_t& next_id) {
  const std::size_t first = s.count;
  const std::size_t room = def.max_particles > s.count ? def.max_particles - s.count : 0;
  schedule(def, st, t1, room);
  const std::size_t n = st.births.size();
  if (n == 0) return first;
  s.append(n);
  const double h = t1 - t0;
  const bool inherit = !def.path.empty() && def.inherit_velocity > 0.0;
  release(def, st, s, first, n,
          [&](std::size_t k) {
            const double t_birth = st.births[k];
            BirthPose b{frame_at(def, t_birth), std::clamp(t1 - t_birth, 0.0, h), inherit, Vec3::Zero()};
            if (inherit) b.velocity = def.inherit_velocity * def.path.velocity(t_birth);
            return b;
          },
          next_id);
  return first;
}

std::size_t emit_sub(const EmitterDef& def, EmitterState& st, ParticleStore& s,
                     const std::vector<SubBirth>& births, std::uint64_t& next_id) {
  const std::size_t first = s.count;
  for (const SubBirth& q : births) {
    const std::size_t room = def.max_particles > s.count ? def.max_particles - s.count : 0;
    const std::size_t n = std::min(q.count, room);
    if (n == 0) continue;
    const std::size_t at = s.append(n);
    Transform f = def.transform;  // the emitter's rotation, placed on the parent
    f.rotation.normalize();
    f.translation = q.position;
    release(def, st, s, at, n, [&](std::size_t) { return BirthPose{f, q.age, true, q.velocity}; }, next_id);
  }
  return first;
}

// ---------------------------------------------------------------------------------------------
// Curves over lifetime

SizeCurve::SizeCurve(const std::vector<SizeKey>& keys) {
  for (const SizeKey& k : keys) {
    t_.push_back(float(k.t));
    size_.push_back(float(k.size));
  }
}

float SizeCurve::eval(float u) const {
  if (u <= t_.front()) return size_.front();
  if (u >= t_.back()) return size_.back();
  const std::size_t k = std::size_t(std::upper_bound(t_.begin(), t_.end(), u) - t_.begin());
  const float span = t_[k] - t_[k - 1];
  const float w = span > 0.f ? (u - t_[k - 1]) / span : 1.f;
  return size_[k - 1] + w * (size_[k] - size_[k - 1]);
}

void SizeCurve::apply(ParticleStore& s, std::size_t begin, std::size_t end) const {
  for (std::size_t i = begin; i < end; ++i) {
    const float u = s.lifetime[i] > 0.f ? s.age[i] / s.lifetime[i] : 1.f;
    s.radius[i] = std::max(float(kMinRadius), s.base_radius[i] * eval(u));
  }
}

void apply_tint(ParticleStore& s, std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i)
    for (std::size_t c = 0; c < 3; ++c) s.color[4 * i + c] *= s.tint[i];
}

// ---------------------------------------------------------------------------------------------
// Validation

namespace {

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }

void check_distribution(const Distribution& d, const std::string& what) {
  if (!std::isfinite(d.mean) || !std::isfinite(d.deviation) || std::isnan(d.min) ||
      std::isnan(d.max))
    fail(what + ": mean and deviation must be finite, min/max not NaN");
  if (d.deviation < 0.0) {
    std::ostringstream m;
    m << what << ".deviation must be >= 0 (got " << d.deviation << ")";
    fail(m.str());
  }
  if (d.uniform && (!std::isfinite(d.min) || !std::isfinite(d.max)))
    fail(what + ": a uniform distribution needs finite min and max");
  if (d.min > d.max) {
    std::ostringstream m;
    m << what << ": min must be <= max (got min " << d.min << ", max " << d.max << ")";
    fail(m.str());
  }
}

template <class T>
void positive(T value, const std::string& what) {
  if (!(value > T(0)) || !std::isfinite(double(value))) {
    std::ostringstream m;
    m << what << " must be > 0 and finite (got " << value << ")";
    fail(m.str());
  }
}

void validate_mesh(const EmitterDef& e, const std::string& sys) {
  const std::string where = sys + ": emitter.mesh";
  if (e.mesh_positions.size() % 3 != 0) fail(where + "_positions must hold 3 floats per vertex");
  if (e.mesh_triangles.empty() || e.mesh_triangles.size() % 3 != 0)
    fail(where + "_triangles must hold 3 indices per triangle, at least one triangle");
  for (float x : e.mesh_positions)
    if (!std::isfinite(x)) fail(where + "_positions must be finite");
  const std::size_t nv = e.mesh_positions.size() / 3;
  double area = 0.0;
  for (std::size_t k = 0; k < e.mesh_triangles.size(); k += 3) {
    Vec3 v[3];
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint32_t vi = e.mesh_triangles[k + c];
      if (vi >= nv) {
        std::ostringstream m;
        m << where << "_triangles[" << k + c << "] = " << vi << " is not a vertex (have " << nv
          << ")";
        fail(m.str());
      }
      v[c] = Vec3(e.mesh_positions[3 * vi], e.mesh_positions[3 * vi + 1],
                  e.mesh_positions[3 * vi + 2]);
    }
    area += 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).norm();
  }
  if (!(area > 0.0)) fail(where + " must have a surface area > 0");
}

}  // namespace

void validate(const ParticleSystemDef& def) {
  const std::string sys = "ParticleSystemDef '" + def.name + "'";
  const EmitterDef& e = def.emitter;
  if (!def.gravity.allFinite()) fail(sys + ": gravity must be finite");
  require_in(def.drag, ranges::kSystemDrag, sys + ": drag");
  require_in(def.drag_quadratic, ranges::kSystemDragQuadratic, sys + ": drag_quadratic");
  if (e.shape == EmitterShape::disk) {
    require_in(e.disk_radius, ranges::kEmitterSize, sys + ": emitter.disk_radius");
  } else if (e.shape == EmitterShape::quad) {
    require_in(e.quad_size[0], ranges::kEmitterSize, sys + ": emitter.quad_size[0]");
    require_in(e.quad_size[1], ranges::kEmitterSize, sys + ": emitter.quad_size[1]");
  } else if (e.shape == EmitterShape::sphere) {
    require_in(e.sphere_radius, ranges::kEmitterSize, sys + ": emitter.sphere_radius");
  } else if (e.shape == EmitterShape::box) {
    for (std::size_t k = 0; k < 3; ++k)
      require_in(e.box_size[k], ranges::kEmitterSize, sys + ": emitter.box_size[" + std::to_string(k) + "]");
  } else if (e.shape == EmitterShape::cube) {
    require_in(e.cube_size, ranges::kEmitterSize, sys + ": emitter.cube_size");
  } else if (e.shape == EmitterShape::mesh) {
    validate_mesh(e, sys);
  } else if (e.shape != EmitterShape::point) {
    fail(sys + ": unknown emitter shape");
  }
  if (!e.transform.translation.allFinite() || !e.transform.rotation.coeffs().allFinite() ||
      !(e.transform.rotation.norm() > 1e-12))
    fail(sys + ": emitter.transform must be finite with a non-zero rotation quaternion");
  validate(e.path, sys + ": emitter.path");
  require_in(e.rate, ranges::kEmitterRate, sys + ": emitter.rate");
  if (std::isnan(e.start_time) || std::isnan(e.stop_time) || !std::isfinite(e.start_time))
    fail(sys + ": emitter.start_time must be finite and stop_time not NaN");
  if (e.stop_time < e.start_time) {
    std::ostringstream m;
    m << sys << ": emitter.stop_time must be >= start_time (got " << e.stop_time << " < "
      << e.start_time << ")";
    fail(m.str());
  }
  check_distribution(e.lifetime, sys + ": emitter.lifetime");
  check_distribution(e.start_speed, sys + ": emitter.start_speed");
  check_distribution(e.spread_deg, sys + ": emitter.spread_deg");
  check_distribution(e.mass, sys + ": emitter.mass");
  check_distribution(e.radius, sys + ": emitter.radius");
  // A uniform draw ignores the mean: it must then be able to draw a positive value.
  positive(e.mass.uniform ? e.mass.max : e.mass.mean,
           sys + (e.mass.uniform ? ": emitter.mass.max" : ": emitter.mass.mean"));
  positive(e.radius.uniform ? e.radius.max : e.radius.mean,
           sys + (e.radius.uniform ? ": emitter.radius.max" : ": emitter.radius.mean"));
  // Stored as floats: a larger mass or radius would be born infinite.
  for (const auto& [d, what] : {std::pair{&e.mass, ": emitter.mass"}, std::pair{&e.radius, ": emitter.radius"}}) {
    const double top = d->uniform ? d->max : d->mean;
    if (top > ranges::kParticleFloatMax) {
      std::ostringstream m;
      m << sys << what << (d->uniform ? ".max" : ".mean") << " must be <= " << ranges::kParticleFloatMax
        << " (got " << top << ")";
      fail(m.str());
    }
  }
  if (e.color_over_lifetime.empty())
    fail(sys + ": emitter.color_over_lifetime needs at least one key");
  for (std::size_t k = 0; k < e.color_over_lifetime.size(); ++k) {
    const ColorKey& c = e.color_over_lifetime[k];
    std::ostringstream where;
    where << sys << ": emitter.color_over_lifetime[" << k << "]";
    if (!(c.t >= 0.0 && c.t <= 1.0)) fail(where.str() + ".t must be in [0, 1]");
    if (k > 0 && c.t < e.color_over_lifetime[k - 1].t)
      fail(where.str() + ".t must not decrease along the gradient");
    for (float v : c.rgba)
      if (!std::isfinite(v)) fail(where.str() + ".rgba must be finite");
  }
  require_in((long long)e.max_particles, ranges::kEmitterMaxParticles, sys + ": emitter.max_particles");
  for (std::size_t k = 0; k < e.bursts.size(); ++k) {
    const Burst& b = e.bursts[k];
    const std::string where = sys + ": emitter.bursts[" + std::to_string(k) + "]";
    require_in(b.time, ranges::kBurstTime, where + ".time");
    require_in(b.repeat_interval, ranges::kBurstRepeatInterval, where + ".repeat_interval");
    if (b.cycles == 0 && !(b.repeat_interval > 0.0))
      fail(where + ": cycles = 0 (forever) needs repeat_interval > 0");
  }
  for (std::size_t k = 0; k < e.size_over_lifetime.size(); ++k) {
    const SizeKey& key = e.size_over_lifetime[k];
    const std::string where = sys + ": emitter.size_over_lifetime[" + std::to_string(k) + "]";
    require_in(key.t, ranges::kSizeKeyT, where + ".t");
    if (k > 0 && key.t < e.size_over_lifetime[k - 1].t)
      fail(where + ".t must not decrease along the curve");
    require_in(key.size, ranges::kSizeKeySize, where + ".size");
  }
  require_in(e.color_deviation, ranges::kEmitterColorDeviation, sys + ": emitter.color_deviation");
  require_in(e.inherit_velocity, ranges::kEmitterInheritVelocity, sys + ": emitter.inherit_velocity");
  const SplitDef& sp = e.split;
  if (sp.enabled) {
    const std::string where = sys + ": emitter.split.";
    require_in((long long)sp.children, ranges::kSplitChildren, where + "children");
    require_in(sp.age, ranges::kSplitAge, where + "age");
    require_in((long long)sp.delay_steps, ranges::kSplitDelaySteps, where + "delay_steps");
    require_in((long long)sp.depth, ranges::kSplitDepth, where + "depth");
    require_in(sp.velocity_fraction, ranges::kSplitVelocityFraction, where + "velocity_fraction");
    require_in(sp.direction_deviation_deg, ranges::kSplitDirectionDeviationDeg, where + "direction_deviation_deg");
    require_in(sp.size_fraction, ranges::kSplitSizeFraction, where + "size_fraction");
    require_in(sp.lifetime_deviation, ranges::kSplitLifetimeDeviation, where + "lifetime_deviation");
  }
}

}  // namespace simreel::sim::detail
