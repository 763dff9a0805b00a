// Emitters (Coutinho §3.8) and the validation of particle-system definitions.
#include "emitter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "validate.hpp"

namespace simreel::sim::detail {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMinMass = 1e-12;   // (kg) floor of a mass draw: drag divides by it
constexpr double kMinRadius = 1e-6;  // (m) floor of a radius draw

/// Number of births up to and including time t, given x = rate * (t - start): birth j (from 0)
/// is at start + (j + 1) / rate, so the count is floor(x) — the same for any cut of [start, t]
/// into frames and steps. The relative epsilon keeps a birth that falls on t (x an integer but
/// computed as 59.999999999) in the step that ends there, whatever the fps.
std::uint64_t births_until(double x) {
  if (!(x > 0.0)) return 0;
  return std::uint64_t(std::floor(x + 1e-9 * std::max(1.0, x)));
}

double draw(Rng& rng, const Distribution& d) {
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
void layout_quad(const EmitterDef& def, EmitterState& st, ParticleStore& s, std::size_t first,
                 std::size_t n) {
  std::vector<double>& local = st.local;  // (n x 2) start points in the emitter frame (m)
  local.resize(2 * n);
  double d_max = 0.0;
  for (std::size_t i = first; i < first + n; ++i) d_max = std::max(d_max, 2.0 * double(s.radius[i]));
  const double lx = def.quad_size[0], ly = def.quad_size[1];
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

}  // namespace

std::size_t emit(const EmitterDef& def, EmitterState& st, ParticleStore& s, double t0, double t1,
                 std::uint64_t& next_id) {
  const std::size_t first = s.count;
  if (!(def.rate > 0.0)) return first;
  const double t_hi = std::min(t1, def.stop_time);
  const std::uint64_t target = births_until(def.rate * (t_hi - def.start_time));
  if (target <= st.scheduled) return first;
  const std::uint64_t due = target - st.scheduled;
  const std::size_t room = def.max_particles > s.count ? def.max_particles - s.count : 0;
  const std::size_t n = std::size_t(std::min<std::uint64_t>(due, room));
  const std::uint64_t j0 = st.scheduled;
  st.scheduled = target;
  if (n == 0) return first;
  s.append(n);

  const double h = t1 - t0;
  // Per-particle draws in a fixed order (the same seed gives the same particles): lifetime,
  // speed, spread, azimuth, mass, radius, then the start point.
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = first + k;
    const double t_birth = def.start_time + double(j0 + k + 1) / def.rate;
    const double age = std::clamp(t1 - t_birth, 0.0, h);
    const double lifetime = std::max(0.0, draw(st.rng, def.lifetime));
    const double speed = draw(st.rng, def.start_speed);
    // A negative polar angle at azimuth phi is the positive one at phi + 180 deg, so draws are
    // folded rather than clamped at 0 (which would send half of them straight along +z).
    const double spread_deg = std::clamp(
        std::clamp(std::abs(st.rng.normal(def.spread_deg.mean, def.spread_deg.deviation)),
                   def.spread_deg.min, def.spread_deg.max),
        0.0, 180.0);
    const double azimuth = 2.0 * kPi * st.rng.uniform();
    const double mass = std::max(kMinMass, draw(st.rng, def.mass));
    const double radius = std::max(kMinRadius, draw(st.rng, def.radius));

    const double theta = spread_deg * (kPi / 180.0);
    const Vec3 dir_local(std::sin(theta) * std::cos(azimuth), std::sin(theta) * std::sin(azimuth),
                         std::cos(theta));
    const Transform f = frame_at(def, t_birth);
    const Vec3 vel = f.rotation * (speed * dir_local);

    s.lifetime[i] = float(lifetime);
    s.age[i] = float(age);
    s.mass[i] = float(mass);
    s.radius[i] = float(radius);
    s.id[i] = next_id++;
    for (int c = 0; c < 3; ++c) s.velocity[3 * i + std::size_t(c)] = float(vel[c]);

    if (def.shape == EmitterShape::disk) {
      // sqrt: uniform over the disk's area, not its radius.
      const double rho = def.disk_radius * std::sqrt(st.rng.uniform());
      const double phi = 2.0 * kPi * st.rng.uniform();
      const Vec3 p = f.translation + f.rotation * Vec3(rho * std::cos(phi), rho * std::sin(phi), 0.0);
      for (int c = 0; c < 3; ++c) s.position[3 * i + std::size_t(c)] = float(p[c]);
    }
  }

  if (def.shape == EmitterShape::quad) {
    layout_quad(def, st, s, first, n);
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = first + k;
      const Transform f = frame_at(def, def.start_time + double(j0 + k + 1) / def.rate);
      const Vec3 p = f.translation + f.rotation * Vec3(st.local[2 * k], st.local[2 * k + 1], 0.0);
      for (int c = 0; c < 3; ++c) s.position[3 * i + std::size_t(c)] = float(p[c]);
    }
  }
  if (s.track_prev)
    std::copy(s.position.begin() + std::ptrdiff_t(3 * first), s.position.end(),
              s.prev_position.begin() + std::ptrdiff_t(3 * first));
  return first;
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

}  // namespace

void validate(const ParticleSystemDef& def) {
  const std::string sys = "ParticleSystemDef '" + def.name + "'";
  const EmitterDef& e = def.emitter;
  if (!def.gravity.allFinite()) fail(sys + ": gravity must be finite");
  if (!std::isfinite(def.drag) || def.drag < 0.0) {
    std::ostringstream m;
    m << sys << ": drag must be >= 0 and finite (got " << def.drag << ")";
    fail(m.str());
  }
  if (def.integrator != Integrator::semi_implicit_euler && def.integrator != Integrator::rk4)
    fail(sys + ": unknown integrator");
  if (e.shape == EmitterShape::disk) {
    positive(e.disk_radius, sys + ": emitter.disk_radius");
  } else if (e.shape == EmitterShape::quad) {
    positive(e.quad_size[0], sys + ": emitter.quad_size[0]");
    positive(e.quad_size[1], sys + ": emitter.quad_size[1]");
  } else {
    fail(sys + ": unknown emitter shape");
  }
  if (!e.transform.translation.allFinite() || !e.transform.rotation.coeffs().allFinite() ||
      !(e.transform.rotation.norm() > 1e-12))
    fail(sys + ": emitter.transform must be finite with a non-zero rotation quaternion");
  validate(e.path, sys + ": emitter.path");
  if (!std::isfinite(e.rate) || e.rate < 0.0) {
    std::ostringstream m;
    m << sys << ": emitter.rate must be >= 0 and finite (got " << e.rate << ")";
    fail(m.str());
  }
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
  positive(e.mass.mean, sys + ": emitter.mass.mean");
  positive(e.radius.mean, sys + ": emitter.radius.mean");
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
  if (e.max_particles == 0) fail(sys + ": emitter.max_particles must be >= 1");
}

}  // namespace simreel::sim::detail
