// Particle-steps per second of the sim hot loop: gravity + viscous drag, semi-implicit Euler,
// one internal step per iteration (1/240 s).
//   no_colliders     integration, ageing and the dead-particle scan only
//   ground_airborne  plus a ground plane every particle is far above (the rejection test)
//   ground_resting   plus a ground plane every particle lies on, sliding (the contact path)
// Figures go in issue notes, never thresholds in tests.
#include <benchmark/benchmark.h>

#include <cstdint>

#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace {

using namespace simreel::sim;

enum class Scene { no_colliders, ground_airborne, ground_resting };

void particle_steps(benchmark::State& state, Scene scene) {
  const auto n = std::size_t(state.range(0));
  World world(WorldDef{1.0 / 240, 1, 0.05});
  if (scene != Scene::no_colliders) {
    PlaneDef ground;
    ground.material = {0.5, 0.3};
    world.add_plane(ground);
  }
  ParticleSystemDef def;
  def.name = "bench";
  def.drag = 1e-4;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = n;
  const auto ps = world.add_particle_system(def);
  Rng rng(42);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p(rng.uniform(-50, 50), rng.uniform(-50, 50),
                 scene == Scene::ground_resting ? 0.01 : rng.uniform(1000, 2000));
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

}  // namespace

BENCHMARK_CAPTURE(particle_steps, no_colliders, Scene::no_colliders)
    ->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(particle_steps, ground_airborne, Scene::ground_airborne)
    ->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(particle_steps, ground_resting, Scene::ground_resting)
    ->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
