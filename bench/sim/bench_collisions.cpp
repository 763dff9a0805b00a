// Collision benchmarks (Coutinho Ch. 2–3). Figures go in issue notes, never thresholds in tests.
//   rain_on_mesh/N/T      N particles raining onto a 100k-triangle height-field mesh, whole step,
//                         T threads (WorldDef::threads); the first 240 steps (1 s: the rain
//                         lands and lies), so that runs compare (the world is not reset)
//   rain_on_mesh_settled/N/T
//                         the same rain's third second (steps 481-720, untimed 480 before): by
//                         then 92 % of the drops lie still on the terrain
//   mesh_broad/N, mesh_broad_narrow/N
//                         the same swept segments against the mesh: AABB-tree query alone
//                         (broad) and query + swept-sphere triangle tests (broad + narrow)
//   internal_world/N/T    N particles in a box with particle–particle collisions, whole step (the
//                         first 10 steps from the same start, so that runs compare),
//                         T threads
//   internal_world_after_first/N/T
//                         the same cloud's steps 2-11: its first step (every array's pages
//                         touched for the first time, no warm start) costs several later ones
//   internal_world_steady/N/T
//                         steps 3-32: past the first touch of the arrays and most of the random
//                         cloud's relaxation, the per-step cost a long simulation sees
//   internal_motion/N     not a timing: how far the same cloud's particles move over steps 1-32,
//                         and how often a candidate-pair list with a skin (rebuilt once any
//                         particle has moved half the skin since it was built) would be
//                         rebuilt: counters rebuilds_<skin>mm over steps 1-10 and 3-32, and the
//                         median and largest step displacement at steps 10 and 32 (mm)
//   internal_grid/N, internal_solve/N
//                         the grid pair search (broad) and the sequential-impulse solve (narrow
//                         and response) of the same particles
//   pile_in_bowl          5,000 particles poured into the bowl for 10 s (the full version of the
//                         test): counters escaped, inside (removed), mean and max speed at the end
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "collision/bvh.hpp"
#include "collision/mesh_grid.hpp"
#include "collision/narrow_phase.hpp"
#include "collision/particle_collisions.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace {

using namespace simreel::sim;

/// Height field of 2 x 224 x 224 = 100,352 triangles over [-50, 50]^2 m with gentle bumps.
MeshDef terrain() {
  MeshDef d;
  const int n = 224;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = -50.0 + 100.0 * i / n, y = -50.0 + 100.0 * j / n;
      d.vertices.emplace_back(x, y, 0.5 * std::sin(0.3 * x) * std::cos(0.2 * y));
    }
  auto at = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      d.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      d.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  d.material = Material(0.3, 0.4);
  return d;
}

/// terrain()'s triangles with their unit normals (local frame = world).
std::vector<detail::Triangle> terrain_triangles() {
  const MeshDef def = terrain();
  std::vector<detail::Triangle> tris;
  for (const auto& t : def.triangles) {
    detail::Triangle x{def.vertices[t[0]], def.vertices[t[1]], def.vertices[t[2]], Vec3::Zero()};
    x.normal = (x.b - x.a).cross(x.c - x.a).normalized();
    tris.push_back(x);
  }
  return tris;
}

void rain(benchmark::State& state, int settle_steps) {
  const auto n = std::size_t(state.range(0));
  World world(WorldDef{1.0 / 240, 1, 0.05, int(state.range(1))});
  world.add_mesh(terrain());
  ParticleSystemDef def;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = n;
  const auto ps = world.add_particle_system(def);
  Rng rng(42);
  for (std::size_t i = 0; i < n; ++i)
    world.spawn_particle(ps, Vec3(rng.uniform(-45, 45), rng.uniform(-45, 45), rng.uniform(0.6, 3.0)),
                         Vec3(0, 0, -rng.uniform(2, 8)), 1e-3, 0.01, 1e9);
  for (int k = 0; k < settle_steps; ++k) world.advance(1.0 / 240);
  for (auto _ : state) {
    world.advance(1.0 / 240);
    benchmark::DoNotOptimize(world.particles(ps).position);
  }
  state.counters["particle_steps"] =
      benchmark::Counter(double(n) * double(state.iterations()), benchmark::Counter::kIsRate);
}
void rain_on_mesh(benchmark::State& state) { rain(state, 0); }
void rain_on_mesh_settled(benchmark::State& state) { rain(state, 480); }

/// One step's segments (start, displacement) of n particles falling near the terrain's surface,
/// in Z-order of where they start when `zorder` (as collide() visits them), else as drawn.
std::vector<std::pair<Vec3, Vec3>> falling_segments(std::size_t n, bool zorder) {
  Rng rng(42);
  std::vector<std::pair<std::uint64_t, std::pair<Vec3, Vec3>>> seg(n);
  for (auto& [code, ad] : seg) {
    ad.first = Vec3(rng.uniform(-45, 45), rng.uniform(-45, 45), rng.uniform(-0.5, 0.6));
    ad.second = Vec3(0, 0, -rng.uniform(2, 8) / 240);
    code = 0;
    const auto qx = std::uint64_t((ad.first.x() + 50) * 10.23), qy = std::uint64_t((ad.first.y() + 50) * 10.23);
    for (int b = 0; b < 10; ++b) code |= (qx >> b & 1) << (2 * b) | (qy >> b & 1) << (2 * b + 1);
  }
  if (zorder) std::stable_sort(seg.begin(), seg.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
  std::vector<std::pair<Vec3, Vec3>> out;
  for (const auto& s : seg) out.push_back(s.second);
  return out;
}

/// Times query(a, d, box lo, box hi, hit, found) over every segment (its box grown by the 1 cm
/// radius), counting segments per second.
template <class Query>
void time_segments(benchmark::State& state, const std::vector<std::pair<Vec3, Vec3>>& segs, const Query& query) {
  std::size_t found = 0;
  for (auto _ : state) {
    for (const auto& [a, d] : segs) {
      const Vec3 b = a + d, g = Vec3::Constant(0.01);
      detail::SweepHit h;
      query(a, d, Vec3(a.cwiseMin(b) - g), Vec3(a.cwiseMax(b) + g), h, found);
      found += std::isfinite(h.s);
    }
    benchmark::DoNotOptimize(found);
  }
  state.counters["segments"] =
      benchmark::Counter(double(segs.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
}

void mesh_phases(benchmark::State& state, bool narrow) {
  const std::vector<detail::Triangle> tris = terrain_triangles();
  const detail::Bvh bvh(tris);
  time_segments(state, falling_segments(std::size_t(state.range(0)), false),
                [&](const Vec3& a, const Vec3& d, const Vec3& lo, const Vec3& hi, detail::SweepHit& h,
                    std::size_t& found) {
                  bvh.query(lo, hi, [&](std::uint32_t t) {
                    if (narrow) {
                      detail::sweep_triangle(tris[t], a, d, 0.01, h);
                    } else {
                      ++found;
                    }
                  });
                });
  state.counters["bvh_depth"] = bvh.depth();
}

/// The same segments against the mesh's uniform grid (MeshGrid, what the particle sweep asks
/// first), visited in Z-order of where they are as collide() does: the grid query alone (broad)
/// and with the swept-sphere triangle tests (broad + narrow).
void mesh_grid_phases(benchmark::State& state, bool narrow) {
  const std::vector<detail::Triangle> tris = terrain_triangles();
  const detail::Bvh bvh(tris);
  const detail::MeshGrid grid(tris, bvh.visit_order());
  time_segments(state, falling_segments(std::size_t(state.range(0)), true),
                [&](const Vec3& a, const Vec3& d, const Vec3& lo, const Vec3& hi, detail::SweepHit& h,
                    std::size_t& found) {
                  const detail::SweepSegment seg(a, d);
                  grid.query(lo, hi, [&](const detail::SweepTriangle& t, std::uint32_t) {
                    if (narrow) {
                      detail::sweep_triangle(t, seg, 0.01, h);
                    } else {
                      ++found;
                    }
                  });
                });
}

/// n particles of radius 1 cm at about 30 % volume fraction in a 3D box with random velocities.
detail::ParticleCollider cloud(std::size_t n) {
  detail::ParticleCollider pc;
  Rng rng(9);
  const double side = std::cbrt(double(n) * 4.19e-6 / 0.3);
  for (std::size_t i = 0; i < n; ++i) {
    pc.x.emplace_back(rng.uniform(0, side), rng.uniform(0, side), rng.uniform(0, side));
    pc.v.emplace_back(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    pc.inv_mass.push_back(1000.0);
    pc.radius.push_back(0.01);
    pc.restitution.push_back(0.5);
    pc.friction.push_back(0.2);
  }
  return pc;
}

/// cloud(n) as a particle system of `world` (no gravity, particle–particle collisions).
ParticleSystemHandle add_cloud(World& world, std::size_t n) {
  ParticleSystemDef def;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = n;
  def.gravity = Vec3::Zero();
  def.collide_particles = true;
  const auto ps = world.add_particle_system(def);
  const detail::ParticleCollider pc = cloud(n);
  for (std::size_t i = 0; i < n; ++i) world.spawn_particle(ps, pc.x[i], pc.v[i], 1e-3, 0.01, 1e9);
  return ps;
}

/// internal_world(state) after `untimed` steps.
void internal(benchmark::State& state, int untimed) {
  const auto n = std::size_t(state.range(0));
  World world(WorldDef{1.0 / 240, 1, 0.05, int(state.range(1))});
  const ParticleSystemHandle ps = add_cloud(world, n);
  for (int k = 0; k < untimed; ++k) world.advance(1.0 / 240);
  for (auto _ : state) {
    world.advance(1.0 / 240);
    benchmark::DoNotOptimize(world.particles(ps).position);
  }
  state.counters["particle_steps"] =
      benchmark::Counter(double(n) * double(state.iterations()), benchmark::Counter::kIsRate);
}
void internal_world(benchmark::State& state) { internal(state, 0); }
void internal_world_after_first(benchmark::State& state) { internal(state, 1); }
void internal_world_steady(benchmark::State& state) { internal(state, 2); }

/// Five steps of internal_world/N/T, then a hash of the positions and velocities (its low 48 bits
/// as a counter): old and new builds and thread counts compared bit for bit.
void internal_hash(benchmark::State& state) {
  const auto n = std::size_t(state.range(0));
  std::uint64_t h = 0;
  for (auto _ : state) {
    World world(WorldDef{1.0 / 240, 1, 0.05, int(state.range(1))});
    const ParticleSystemHandle ps = add_cloud(world, n);
    for (int s = 0; s < 5; ++s) world.advance(1.0 / 240);
    const ParticleView v = world.particles(ps);
    h = 0xcbf29ce484222325ull;
    const auto mix = [&](const float* p, std::size_t m) {
      const auto* b = reinterpret_cast<const unsigned char*>(p);
      for (std::size_t k = 0; k < m * sizeof(float); ++k) h = (h ^ b[k]) * 0x100000001b3ull;
    };
    mix(v.position, 3 * v.count);
    mix(v.velocity, 3 * v.count);
  }
  state.counters["hash48"] = double(h & ((std::uint64_t{1} << 48) - 1));
}

/// internal_motion(state): the cloud of internal_world/N/1 advanced 32 steps, each particle's
/// displacement per step and since a (simulated) skin list was last built, for skins of 2, 5, 10
/// and 20 mm (0.1 to 1 particle diameters). A list built at step b serves the steps after it
/// while every particle has moved less than half the skin since b (Verlet 1967; the usual
/// criterion, e.g. LAMMPS's neigh_modify check), so `rebuilds` counts the steps that need a new
/// one. Counts and quantiles only, never thresholds (figures go in docs/benchmarks.md).
void internal_motion(benchmark::State& state) {
  const auto n = std::size_t(state.range(0));
  const double skins_mm[] = {2, 5, 10, 20};
  for (auto _ : state) {
    World world(WorldDef{1.0 / 240, 1, 0.05, 1});
    const ParticleSystemHandle ps = add_cloud(world, n);
    const auto positions = [&] {
      const ParticleView v = world.particles(ps);
      return std::vector<float>(v.position, v.position + 3 * v.count);
    };
    const auto distance = [](const std::vector<float>& a, const std::vector<float>& b,
                             std::size_t i) {
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double d = double(a[3 * i + std::size_t(k)]) - double(b[3 * i + std::size_t(k)]);
        d2 += d * d;
      }
      return std::sqrt(d2);
    };
    std::vector<float> last = positions();
    std::vector<std::vector<float>> built(std::size(skins_mm), last);
    int early[std::size(skins_mm)] = {}, later[std::size(skins_mm)] = {};
    std::vector<double> step_mm(n);
    for (int s = 1; s <= 32; ++s) {
      world.advance(1.0 / 240);
      const std::vector<float> now = positions();
      for (std::size_t i = 0; i < n; ++i) step_mm[i] = 1e3 * distance(now, last, i);
      for (std::size_t k = 0; k < std::size(skins_mm); ++k) {
        double moved = 0;
        for (std::size_t i = 0; i < n; ++i) moved = std::max(moved, distance(now, built[k], i));
        if (1e3 * moved >= 0.5 * skins_mm[k]) {  // this step needs a fresh list
          built[k] = now;
          early[k] += s <= 10;
          later[k] += s >= 3;
        }
      }
      if (s == 10 || s == 32) {
        std::vector<double> sorted = step_mm;
        std::sort(sorted.begin(), sorted.end());
        const std::string at = "step" + std::to_string(s);
        state.counters[at + "_median_mm"] = sorted[n / 2];
        state.counters[at + "_max_mm"] = sorted.back();
      }
      last = now;
    }
    for (std::size_t k = 0; k < std::size(skins_mm); ++k) {
      const std::string skin = std::to_string(int(skins_mm[k])) + "mm";
      state.counters["rebuilds_" + skin + "_steps1-10"] = early[k];
      state.counters["rebuilds_" + skin + "_steps3-32"] = later[k];
    }
  }
}

void internal_phase(benchmark::State& state, bool solve) {
  const auto n = std::size_t(state.range(0));
  detail::ParticleCollider pc = cloud(n);
  pc.find_contacts(0.05);
  const std::vector<Vec3> v0 = pc.v;
  for (auto _ : state) {
    if (solve) {
      pc.v = v0;
      for (auto& c : pc.contacts) {  // cold start
        c.pn = 0.0;
        c.pt = Vec3::Zero();
      }
      pc.solve();
    } else {
      pc.find_contacts(0.05);
    }
    benchmark::DoNotOptimize(pc.contacts.data());
  }
  state.counters["contacts"] = double(pc.contacts.size());
  state.counters["particle_steps"] =
      benchmark::Counter(double(n) * double(state.iterations()), benchmark::Counter::kIsRate);
}

void pile_in_bowl(benchmark::State& state) {
  // Same bowl as assets/models/bowl.obj's inner shell (radius 0.3 m, rim at z = 0).
  const double R = 0.3, kPi = std::numbers::pi;
  for (auto _ : state) {
    World world;
    MeshDef d;
    const int rings = 16, sectors = 48;
    d.vertices.emplace_back(0, 0, -R);
    for (int i = 1; i <= rings; ++i)
      for (int j = 0; j < sectors; ++j) {
        const double th = 0.5 * kPi * i / rings, ph = 2 * kPi * j / sectors;
        d.vertices.emplace_back(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph), -R * std::cos(th));
      }
    auto at = [&](int i, int j) { return std::uint32_t(1 + (i - 1) * sectors + (j % sectors)); };
    for (int j = 0; j < sectors; ++j) d.triangles.push_back({0, at(1, j), at(1, j + 1)});
    for (int i = 1; i < rings; ++i)
      for (int j = 0; j < sectors; ++j) {
        d.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        d.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    d.material = Material(0.3, 0.5);
    world.add_mesh(d);
    ParticleSystemDef def;
    def.collide_particles = true;
    def.particle_restitution = 0.2;
    def.particle_friction = 0.3;
    def.emitter.rate = 1000;
    def.emitter.stop_time = 5.0;
    def.emitter.disk_radius = 0.08;
    def.emitter.transform.translation = Vec3(0, 0, 0.15);
    def.emitter.transform.rotation = Quat(Eigen::AngleAxisd(kPi, Vec3::UnitX()));
    def.emitter.start_speed = {0.5, 0.0, 0.0};
    def.emitter.lifetime = {1e6, 0, 0};
    def.emitter.radius = {0.008, 0, 1e-6};
    def.emitter.max_particles = 5000;
    const auto ps = world.add_particle_system(def);
    world.advance(10.0);
    const ParticleView v = world.particles(ps);
    double escaped = 0, speed = 0, max_speed = 0;
    for (std::size_t i = 0; i < v.count; ++i) {
      const Vec3 x(v.position[3 * i], v.position[3 * i + 1], v.position[3 * i + 2]);
      escaped += x.norm() > R - 0.008 + 1e-3 || x.z() > 0.02;
      const double s = Vec3(v.velocity[3 * i], v.velocity[3 * i + 1], v.velocity[3 * i + 2]).norm();
      speed += s / double(v.count);
      max_speed = std::max(max_speed, s);
    }
    state.counters["particles"] = double(v.count);
    state.counters["escaped"] = escaped;
    state.counters["inside_removed"] = double(world.removed_inside_count(ps));
    state.counters["mean_speed_m_s"] = speed;
    state.counters["max_speed_m_s"] = max_speed;
  }
}

}  // namespace

BENCHMARK(rain_on_mesh)->Args({100'000, 1})->Args({100'000, 2})->Iterations(240)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(rain_on_mesh_settled)->Args({100'000, 1})->Args({100'000, 2})->Iterations(240)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(mesh_phases, mesh_broad, false)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_phases, mesh_broad_narrow, true)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_grid_phases, mesh_grid_broad, false)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_grid_phases, mesh_grid_broad_narrow, true)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(internal_world)->Args({100'000, 1})->Args({100'000, 2})->Iterations(10)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(internal_world_after_first)->Args({100'000, 1})->Args({100'000, 2})->Iterations(10)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(internal_world_steady)->Args({100'000, 1})->Args({100'000, 2})->Iterations(30)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(internal_motion)->Arg(100'000)->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(internal_hash)->Args({30'000, 1})->Args({30'000, 2})->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(internal_phase, internal_grid, false)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(internal_phase, internal_solve, true)->Arg(100'000)->Unit(benchmark::kMillisecond);
BENCHMARK(pile_in_bowl)->Iterations(1)->Unit(benchmark::kSecond);
