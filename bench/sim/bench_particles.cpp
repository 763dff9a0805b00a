// Particle-steps per second of the sim hot loops, one internal step (1/240 s) per iteration.
//   no_colliders     gravity + drag, semi-implicit Euler: integration, ageing, the dead scan
//   ground_airborne  plus a ground plane every particle is far above (the rejection test)
//   ground_resting   plus a ground plane every particle lies on, sliding (the contact path)
//   curl_noise       gravity + drag + a curl-noise field (general force path, semi-implicit)
//   pair_forces      gravity + Coulomb/gravitational pair forces with a 0.5 m cut-off over the
//                    grid (~8 neighbours per particle), semi-implicit Euler
// The second argument is the thread count (WorldDef::threads). Figures go in issue notes,
// never thresholds in tests.
#include <benchmark/benchmark.h>

#include <cstdint>

#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace {

using namespace simreel::sim;

enum class Scene { no_colliders, ground_airborne, ground_resting, curl_noise, pair_forces };

void particle_steps(benchmark::State& state, Scene scene) {
  const auto n = std::size_t(state.range(0));
  World world(WorldDef{1.0 / 240, 1, 0.05, int(state.range(1))});
  if (scene == Scene::ground_airborne || scene == Scene::ground_resting) {
    PlaneDef ground;
    ground.material = {0.5, 0.3};
    world.add_plane(ground);
  }
  ParticleSystemDef def;
  def.name = "bench";
  def.drag = 1e-4;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = n;
  if (scene == Scene::pair_forces) {
    def.charge = Distribution{1e-6, 1e-6};
    def.pair_forces = {1e-3, 8.988e9, 0.5, 1e-3};
  }
  const auto ps = world.add_particle_system(def);
  if (scene == Scene::curl_noise) {
    ForceFieldDef f;
    f.kind = FieldKind::curl_noise;
    f.amplitude = 2.0;
    f.frequency = 0.2;
    f.scroll = Vec3(0, 0, 0.3);
    world.add_force_field(f);
  }
  // Pair forces: a density of ~16 particles per m³ (8 inside each cut-off sphere).
  const double side = scene == Scene::pair_forces ? std::cbrt(double(n) / 16.0) : 100.0;
  Rng rng(42);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p(rng.uniform(-side / 2, side / 2), rng.uniform(-side / 2, side / 2),
                 scene == Scene::ground_resting ? 0.01
                 : scene == Scene::pair_forces  ? 1000 + rng.uniform(0, side)
                                                : rng.uniform(1000, 2000));
    const Vec3 v(rng.uniform(-5, 5), rng.uniform(-5, 5),
                 scene == Scene::ground_resting ? 0.0 : rng.uniform(-5, 5));
    world.spawn_particle(ps, p, v, 1e-3, 0.01, 1e9);
  }
  for (auto _ : state) {
    world.advance(1.0 / 240);
    benchmark::DoNotOptimize(world.particles(ps).position);
  }
  state.counters["particle_steps"] =
      benchmark::Counter(double(n) * double(state.iterations()), benchmark::Counter::kIsRate);
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int threads : {1, 2})
    for (int n : {10'000, 100'000, 1'000'000}) b->Args({n, threads});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK_CAPTURE(particle_steps, no_colliders, Scene::no_colliders)->Apply(sizes);
BENCHMARK_CAPTURE(particle_steps, ground_airborne, Scene::ground_airborne)
    ->Args({100'000, 1})->Args({1'000'000, 1})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(particle_steps, ground_resting, Scene::ground_resting)
    ->Args({100'000, 1})->Args({1'000'000, 1})->Args({100'000, 2})
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(particle_steps, curl_noise, Scene::curl_noise)->Apply(sizes);
BENCHMARK_CAPTURE(particle_steps, pair_forces, Scene::pair_forces)
    ->Args({100'000, 1})->Args({100'000, 2})->Unit(benchmark::kMillisecond)->UseRealTime();
