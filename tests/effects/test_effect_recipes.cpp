// The effect presets (Coutinho §3.9.1) checked on the simulated state: each knob does what it
// says in the physics. Scenes are built the way users write them (an "effect" emitter in scene
// JSON), so the recipe, the override mechanism and the engine are tested together.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/effects/physics.hpp"

using simreel::app::json;
namespace app = simreel::app;
namespace sim = simreel::sim;

namespace {

app::SceneWorld world_of(const json& emitter, double max_step = 1.0 / 240.0) {
  json doc = {{"seed", 4}, {"simulation", {{"max_step", max_step}}}, {"emitters", json::array({emitter})}};
  return app::build_world(app::scene_from_json(doc, "effect_test.json"));
}

std::size_t system_named(const app::SceneWorld& sw, const std::string& name) {
  for (std::size_t i = 0; i < sw.systems.size(); ++i)
    if (sw.world.definition(sw.systems[i]).name == name) return i;
  ADD_FAILURE() << "no system " << name;
  return 0;
}

}  // namespace

TEST(EffectRecipes, RainReachesItsTerminalVelocityAndDriftsWithTheWind) {
  // Drops released at rest: gravity plus the derived quadratic drag c_2 = ½ ρ_air C_d π r² must
  // bring them to v_t = √(m g / c_2) of a 2 mm sphere (6.7 m/s; a real drop falls at 6.5),
  // horizontally to the wind. v = v_t tanh(g t / v_t): after 4 s within 1e-4 of it.
  const double d_mm = 2.0;
  const double vt = std::sqrt(simreel::effects::drop_mass(d_mm) * 9.81 /
                              simreel::effects::sphere_quadratic_drag(d_mm));
  EXPECT_NEAR(vt, simreel::effects::raindrop_terminal_velocity(d_mm), 0.04 * vt);
  auto sw = world_of({{"effect", "rain"}, {"center", {0, 0, 0}}, {"area_m", {2, 2}}, {"height_m", 200},
                      {"intensity_mm_h", 1}, {"drop_diameter_mm", d_mm}, {"wind_m_s", {3, 0, 0}},
                      {"overrides", {{"start_speed", 0.0}, {"collide", false}, {"stop_time", 0.5}}}});
  for (int f = 0; f < 4 * 30; ++f) sw.world.advance(1.0 / 30);
  const sim::ParticleView v = sw.world.particles(sw.systems[0]);
  ASSERT_GT(v.count, 20u);
  for (std::size_t i = 0; i < v.count; ++i) {
    EXPECT_NEAR(-v.velocity[3 * i + 2], vt, 0.01 * vt) << "drop " << i;
    EXPECT_NEAR(v.velocity[3 * i], 3.0, 0.01 * 3.0) << "drop " << i;
  }
}

TEST(EffectRecipes, SprinklerApexMatchesMaxHeight) {
  // v0 = sqrt(2 g h) / sin(elevation): the drops' apex is h above the nozzle, vertical or tilted.
  // The override (a JSON merge patch) zeroes only the speed deviation, keeping the derived mean.
  for (double elevation : {90.0, 55.0}) {
    const double h = 1.6, z0 = 0.2;
    auto sw = world_of({{"effect", "sprinkler"}, {"position", {0, 0, z0}}, {"max_height_m", h},
                        {"elevation_deg", elevation}, {"aperture_deg", 0}, {"rotation_rpm", 0},
                        {"flow_drops_s", 50},
                        {"overrides", {{"collide", false}, {"start_speed", {{"deviation", 0}}}}}},
                       1.0 / 1000.0);
    double apex = -1e9;
    for (int s = 0; s < 1500; ++s) {
      sw.world.advance(1.0 / 1000.0);
      const sim::ParticleView v = sw.world.particles(sw.systems[0]);
      for (std::size_t i = 0; i < v.count; ++i) apex = std::max(apex, double(v.position[3 * i + 2]));
    }
    EXPECT_NEAR(apex - z0, h, 0.02 * h) << "elevation " << elevation;
  }
}

TEST(EffectRecipes, FireSmokeRunsYellowOrangeGreyDarkGreyAndMaterialSetsTheStages) {
  // Classify each smoke puff's colour by its normalised age; the stages must appear in order, and
  // a sooty material (rubber) must turn dark sooner than a clean one (paper).
  auto first_dark_age = [](const std::string& material) {
    auto sw = world_of({{"effect", "fire_smoke"}, {"material", material}, {"dissipation_s", 3},
                        {"turbulence_m_s", 0}});
    const std::size_t smoke = system_named(sw, "fire_smoke/smoke");
    for (int f = 0; f < 75; ++f) sw.world.advance(1.0 / 30);
    const sim::ParticleView v = sw.world.particles(sw.systems[smoke]);
    std::vector<std::pair<float, int>> staged;  // (age / lifetime, stage 0..3)
    for (std::size_t i = 0; i < v.count; ++i) {
      const float* c = &v.color[4 * i];
      if (c[3] < 0.02f) continue;  // fully faded: no colour to judge
      const float lum = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
      const float sat = c[0] - c[2];
      const int stage = sat > 0.5f && c[1] > 0.7f * c[0] ? 0     // yellow: red ~ green >> blue
                        : sat > 0.5f                     ? 1     // orange: red > green >> blue
                        : lum > 0.14f                    ? 2     // grey
                                                         : 3;    // dark grey
      // Wood smoke thins out dark grey, never pitch black (issue 14).
      EXPECT_GT(lum, 0.1f) << material << " puff at age " << v.age[i] / v.lifetime[i];
      staged.emplace_back(v.age[i] / v.lifetime[i], stage);
    }
    std::sort(staged.begin(), staged.end());
    int seen = 0, max_stage = 0;
    for (const auto& [u, stage] : staged) {
      EXPECT_GE(stage, max_stage - 0) << material << " at u = " << u;  // never back to a lighter stage
      max_stage = std::max(max_stage, stage);
      seen |= 1 << stage;
    }
    EXPECT_EQ(seen, 0b1111) << material << ": every stage appears";
    for (const auto& [u, stage] : staged)
      if (stage >= 2) return u;
    return 1.0f;
  };
  const float paper = first_dark_age("paper"), rubber = first_dark_age("rubber");
  EXPECT_LT(rubber, paper);
}

TEST(EffectRecipes, ExplosionParticleCountFollowsTheSplitParameters) {
  // One burst of n fragments: n sparks, and n / 4 smoke puffs each of which splits twice (depth 2)
  // into `split_children` children, the parent living on: (children + 1)^2 puffs per puff.
  for (long long children : {0LL, 2LL, 3LL}) {
    const long long n = 400;
    auto sw = world_of({{"effect", "explosion"}, {"particles", n}, {"split_children", children},
                        {"time_s", 0.1}, {"dissipation_s", 10}});
    for (int f = 0; f < 12; ++f) sw.world.advance(1.0 / 30);  // t = 0.4 s: splits done, none dead
    const auto sparks = sw.systems[system_named(sw, "explosion/sparks")];
    const auto smoke = sw.systems[system_named(sw, "explosion/smoke")];
    EXPECT_EQ(sw.world.emitted_count(sparks), std::uint64_t(n));
    const std::uint64_t expected = std::uint64_t(n / 4) * std::uint64_t((children + 1) * (children + 1));
    EXPECT_EQ(sw.world.emitted_count(smoke), expected) << "children " << children;
    EXPECT_EQ(sw.world.particles(smoke).count, expected) << "children " << children;
  }
}

TEST(EffectRecipes, SmokeRisesAtItsRiseSpeedAndSpreadsAsAWideningCone) {
  const double rise = 0.8;
  auto sw = world_of({{"effect", "smoke"}, {"rise_speed_m_s", rise}, {"dissipation_s", 8},
                      {"turbulence_m_s", 0}, {"source_radius_m", 0.1}});
  for (int f = 0; f < 6 * 30; ++f) sw.world.advance(1.0 / 30);
  const sim::ParticleView v = sw.world.particles(sw.systems[0]);
  ASSERT_GT(v.count, 500u);
  // Radial spread (rms distance from the axis) by height band, and the mean rise speed.
  double r2[3] = {0, 0, 0}, n[3] = {0, 0, 0}, vz = 0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const double x = v.position[3 * i], y = v.position[3 * i + 1], z = v.position[3 * i + 2];
    vz += v.velocity[3 * i + 2];
    const int band = z < 1.0 ? -1 : z < 1.5 ? 0 : z < 2.5 ? 1 : z < 3.5 ? 2 : -1;
    if (band < 0) continue;
    r2[band] += x * x + y * y;
    n[band] += 1;
  }
  ASSERT_GT(n[0], 20);
  ASSERT_GT(n[2], 20);
  const double s0 = std::sqrt(r2[0] / n[0]), s1 = std::sqrt(r2[1] / n[1]), s2 = std::sqrt(r2[2] / n[2]);
  EXPECT_LT(s0, s1);
  EXPECT_LT(s1, s2);
  // The vertical speed relaxes to the rise speed (the upward force balances drag, §3.9.1); split
  // children move off-axis at the same speed, so the mean vertical part is a little below it.
  EXPECT_NEAR(vz / double(v.count), rise, 0.1 * rise);
}

TEST(EffectRecipes, BadKnobsNameTheFileAndPointer) {
  auto errors_of = [](const json& emitter) {
    try {
      app::scene_from_json(json{{"emitters", json::array({emitter})}}, "fx.json");
    } catch (const app::SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string e = errors_of({{"effect", "rain"}, {"intensity_mm_h", 1000}});
  EXPECT_NE(e.find("fx.json: /emitters/0/intensity_mm_h: expected a number in [0.1, 300]"), std::string::npos) << e;
  e = errors_of({{"effect", "rian"}});
  EXPECT_NE(e.find("fx.json: /emitters/0/effect"), std::string::npos) << e;
  EXPECT_NE(e.find("rain"), std::string::npos) << e;
  e = errors_of({{"effect", "smoke"}, {"rise_sped_m_s", 1}});
  EXPECT_NE(e.find("did you mean \"rise_speed_m_s\""), std::string::npos) << e;
  e = errors_of({{"effect", "fire_smoke"}, {"material", "plastic"}});
  EXPECT_NE(e.find("/emitters/0/material"), std::string::npos) << e;
  // Overrides are checked like hand-written keys, at their own pointer.
  e = errors_of({{"effect", "jet"}, {"overrides", {{"rat", 5}}}});
  EXPECT_NE(e.find("fx.json: /emitters/0/overrides/rat: unknown key \"rat\"; did you mean \"rate\"?"), std::string::npos) << e;
  e = errors_of({{"effect", "fire_smoke"}, {"overrides", {{"rate", 5}}}});
  EXPECT_NE(e.find("expected a role name (smoke, core)"), std::string::npos) << e;
  EXPECT_EQ(errors_of({{"effect", "fire_smoke"}, {"overrides", {{"core", {{"rate", 5}}}}}}), "");
}
