// The collision pass's memo of responses (collision/collide_memo.hpp) changes no result: particles
// raining onto and settling on a bumpy mesh terrain beside a box and a sphere, with and without the
// memo, give the same floats at every step (Coutinho §3.4 swept sphere, §3.6.1 impulse, §3.6.3
// resting contact), at one and two threads, through compaction, and when the environment changes
// under particles at rest (gravity, a material, a moved collider); and the memo is used (most of
// the particles at rest are not swept again), so the comparison is not empty.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "collision/collide_memo.hpp"
#include "collision/collider_impl.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

double height(double x, double y) { return 0.1 * std::sin(3.0 * x) * std::cos(2.0 * y); }

/// Puts a static collider at `pose`, at both ends of the step (as the world does for a body
/// that does not move: its start-of-step pose is its pose).
void place(detail::Collider& c, const Transform& pose) {
  c.follow(pose, Vec3::Zero(), Vec3::Zero());
  c.follow(pose, Vec3::Zero(), Vec3::Zero());
}

/// The box's pose: centre at height z (m), top at z + 0.15, tilted by `tilt` (rad) about x.
Transform box_pose(double z, double tilt) {
  return Transform{Vec3(0.5, 0.4, z), Quat(Eigen::AngleAxisd(tilt, Vec3::UnitX()) *
                                            Eigen::AngleAxisd(0.3, Vec3::UnitZ()))};
}

/// A 48 x 48 height field over [-2, 2]^2 m (4,608 triangles), a static box and a static sphere on it.
std::vector<detail::Collider> terrain_scene() {
  ShapeDef md;
  md.type = ShapeType::mesh;
  test::fill_height_field(md, 48, 2.0, height);
  md.material = Material(0.3, 0.4);
  std::vector<detail::Collider> cols;
  cols.push_back(detail::make_collider(md, "terrain"));
  place(cols.back(), Transform{});
  cols.push_back(detail::make_collider(ShapeDef::box(Vec3(0.3, 0.2, 0.15)), "box"));
  place(cols.back(), box_pose(0.1, 0.0));
  cols.push_back(detail::make_collider(ShapeDef::sphere(0.25), "sphere"));
  place(cols.back(), Transform{Vec3(-0.7, -0.5, 0.1), Quat::Identity()});
  return cols;
}

/// n particles over the terrain: most just above it and slow (they settle within a few steps),
/// the others dropped from up to 1 m; some at rest on the box's top and near the sphere's; some
/// with short lives (the store compacts them away mid-run).
detail::ParticleStore make_store(std::size_t n) {
  detail::ParticleStore s;
  s.reserve(n);
  s.append(n);
  Rng rng(5);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rng.uniform(0.005, 0.02);
    const double x = rng.uniform(-1.9, 1.9), y = rng.uniform(-1.9, 1.9);
    const bool dropped = i % 5 == 0;
    const double z = height(x, y) + r + (dropped ? rng.uniform(0.1, 1.0) : rng.uniform(0.0, 0.01));
    const Vec3 v0(rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), dropped ? -rng.uniform(0, 3) : 0.0);
    double p[3] = {x, y, z};
    if (i % 11 == 0) {  // on the box's top (z = 0.25), at rest
      const double u = rng.uniform(-0.25, 0.25), w = rng.uniform(-0.15, 0.15);
      p[0] = 0.5 + std::cos(0.3) * u - std::sin(0.3) * w;
      p[1] = 0.4 + std::sin(0.3) * u + std::cos(0.3) * w;
      p[2] = 0.25 + r + 1e-4;
    } else if (i % 13 == 0) {  // near the sphere's top, within the angle static friction holds
      const double dx = rng.uniform(-0.04, 0.04), dy = rng.uniform(-0.04, 0.04);
      p[0] = -0.7 + dx;
      p[1] = -0.5 + dy;
      p[2] = 0.1 + std::sqrt((0.25 + r) * (0.25 + r) - dx * dx - dy * dy) + 1e-4;
    }
    const Vec3 v = i % 11 == 0 || i % 13 == 0 ? Vec3::Zero() : v0;
    for (std::size_t a = 0; a < 3; ++a) {
      s.position[3 * i + a] = float(p[a]);
      s.velocity[3 * i + a] = float(v[a]);
    }
    s.radius[i] = float(r);
    s.mass[i] = float(rng.uniform(1e-4, 1e-2));
    s.age[i] = 1.0f;
    s.lifetime[i] = i % 7 == 0 ? float(rng.uniform(1.05, 1.5)) : 100.0f;
  }
  return s;
}

struct MemoRun {
  detail::ParticleStore s;
  std::vector<detail::Collider> cols = terrain_scene();
  detail::ForceParams f{};
  detail::CollideMemo memo;
  bool use_memo;
  std::size_t reused = 0;
  MemoRun(std::size_t n, bool memo_on) : s(make_store(n)), use_memo(memo_on) {
    f.gravity[2] = -9.81f;
    f.drag = 1e-5f;
  }
  void step(double h, int threads) {
    ASSERT_FALSE(detail::integrate(s, 0, s.count, h, f, Integrator::semi_implicit_euler, threads));
    detail::CollisionContext ctx;
    ctx.threads = threads;
    ctx.memo = use_memo ? &memo : nullptr;
    detail::collide(s, 0, s.count, h, cols, ctx, f);
    if (use_memo) reused += memo.reused;
    s.compact();
  }
};

/// Steps both runs `steps` times (calling change(run) on both before step `at`), comparing every
/// particle's floats after each step; returns the responses the memo reused.
template <class Change>
std::size_t compare(std::size_t n, int steps, int threads, int at, const Change& change) {
  const double h = 1.0 / 240;
  MemoRun plain(n, false), memo(n, true);
  for (int k = 0; k < steps; ++k) {
    if (k == at) {
      change(plain);
      change(memo);
    }
    plain.step(h, threads);
    memo.step(h, threads);
    EXPECT_EQ(plain.s.count, memo.s.count);
    if (plain.s.count != memo.s.count) return memo.reused;
    const std::size_t bytes = 3 * plain.s.count * sizeof(float);
    const bool same = std::memcmp(plain.s.position.data(), memo.s.position.data(), bytes) == 0 &&
                      std::memcmp(plain.s.velocity.data(), memo.s.velocity.data(), bytes) == 0;
    EXPECT_TRUE(same) << "step " << k << ", " << threads << " thread(s)";
    if (!same) return memo.reused;
  }
  std::printf("  %zu particles, %d steps, %d thread(s): %zu responses reused (%.0f %% of particle-steps)\n",
              n, steps, threads, memo.reused, 100.0 * double(memo.reused) / (double(n) * steps));
  return memo.reused;
}

TEST(CollideMemo, SameFloatsAsSweepingEveryParticleEveryStep) {
  // 6,000 particles: the Z-ordered pass of a mesh scene; 150 steps (0.6 s). Most of the
  // particles are at rest well before the end, and those the memo answers.
  const auto none = [](MemoRun&) {};
  const std::size_t reused = compare(6000, 150, 1, -1, none);
  EXPECT_GT(reused, 6000u * 150u / 4) << "the memo should answer most resting particles";
  // 1,000: the unordered pass (below the Z-order's threshold).
  EXPECT_GT(compare(1000, 120, 1, -1, none), 1000u * 120u / 4);
}

TEST(CollideMemo, SameFloatsOnTwoThreads) {
  // Above kParallelMin: the pass splits over the threads, each particle's entry its own.
  const auto none = [](MemoRun&) {};
  EXPECT_GT(compare(20000, 60, 2, -1, none), 0u);
}

TEST(CollideMemo, AChangedEnvironmentSweepsAgain) {
  // Each change comes after 100 steps, when most particles lie still on a remembered response
  // that is no longer right: gravity tilted (they slide), more drag, the terrain's friction
  // gone, the box lowered by 0.05 mm (less than a step's fall, so its particles stay near it and
  // land on it lower down) or tilted under the particles on it. Any entry reused across the
  // change would leave a particle where the old environment put it (shown by breaking the
  // environment check: each case but the two force changes, which change the integrated input
  // itself, then fails).
  const int at = 100, steps = 130;
  EXPECT_GT(compare(6000, steps, 1, at, [](MemoRun& r) { r.f.gravity[0] = 4.0f; }), 0u);
  EXPECT_GT(compare(6000, steps, 1, at, [](MemoRun& r) { r.f.drag = 2e-3f; }), 0u);
  EXPECT_GT(compare(6000, steps, 1, at, [](MemoRun& r) {
              r.cols[0].material.friction = 0.0;
              r.cols[0].material.static_friction = 0.0;
            }),
            0u);
  EXPECT_GT(compare(6000, steps, 1, at, [](MemoRun& r) { place(r.cols[1], box_pose(0.09995, 0.0)); }), 0u);
  EXPECT_GT(compare(6000, steps, 1, at, [](MemoRun& r) { place(r.cols[1], box_pose(0.1, 0.02)); }), 0u);
}

TEST(CollideMemo, ALoadedStateContinuesAsTheSavedWorld) {
  // Through World: drops on a mesh terrain, some dying (the count changes). A state saved at
  // step 40 and loaded into a world whose memo has run on to step 160 (other particles, other
  // entries) continues exactly as the world it was saved from, and as a fresh world that loads
  // it: the memo's entries neither leak across the load nor index past its particles.
  const auto make = [] {
    auto w = std::make_unique<World>(WorldDef{1.0 / 240, 1, 0.05, 1});
    MeshDef md;
    test::fill_height_field(md, 24, 2.0, height);
    md.material = Material(0.3, 0.4);
    w->add_mesh(md);
    ParticleSystemDef def;
    def.emitter.rate = 0.0;
    def.emitter.max_particles = 5000;
    const auto ps = w->add_particle_system(def);
    Rng rng(3);
    for (int i = 0; i < 5000; ++i) {
      const double x = rng.uniform(-1.9, 1.9), y = rng.uniform(-1.9, 1.9);
      w->spawn_particle(ps, Vec3(x, y, height(x, y) + rng.uniform(0.01, 0.3)), Vec3::Zero(), 1e-3,
                        0.01, i % 3 == 0 ? rng.uniform(0.2, 0.6) : 100.0);
    }
    return w;
  };
  auto a = make();
  std::string at40;
  for (int k = 0; k < 160; ++k) {
    if (k == 40) a->save_state(at40);
    a->advance(1.0 / 240);
  }
  const std::uint64_t at160 = a->state_hash();
  a->load_state(at40);  // a's memo holds step 160's entries, for fewer particles
  auto b = make();
  b->load_state(at40);
  for (int k = 40; k < 160; ++k) {
    a->advance(1.0 / 240);
    b->advance(1.0 / 240);
  }
  EXPECT_EQ(a->state_hash(), at160);
  EXPECT_EQ(b->state_hash(), at160);
}

}  // namespace
}  // namespace simreel::sim
