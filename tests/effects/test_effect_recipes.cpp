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

// Crackle: every star (not its trail sparks) that dies gives birth to 30 flashes in
// <name>/crackle0, born at the dying star (within its sphere_radius 5 cm plus what star and flash
// travel in the rest of one internal step), never before the burst; with crackle 0 there is no
// crackle system. One advance() per internal step, so "dying" = present before it, gone after.
TEST(EffectRecipes, FireworksCrackleIsBornAtTheDyingStarsAfterTheBurst) {
  const double h = 1.0 / 240.0;
  const long long stars = 60;
  const json fw = {{"effect", "fireworks"}, {"name", "fw"}, {"shells", 1}, {"stars", stars},
                   {"burst_height_m", 8}, {"crackle", 1.0}};
  auto sw = world_of(fw, h);
  const auto star_sys = sw.systems[system_named(sw, "fw/stars0")];
  const auto crackle_sys = sw.systems[system_named(sw, "fw/crackle0")];
  struct Star {
    std::uint64_t id;
    sim::Vec3 x, v;
  };
  std::vector<Star> before;
  auto snapshot = [&] {
    const sim::ParticleView v = sw.world.particles(star_sys);
    std::vector<Star> out;
    for (std::size_t i = 0; i < v.count; ++i)
      out.push_back({v.id[i], sim::Vec3(v.position[3 * i], v.position[3 * i + 1], v.position[3 * i + 2]),
                     sim::Vec3(v.velocity[3 * i], v.velocity[3 * i + 1], v.velocity[3 * i + 2])});
    return out;
  };
  double first_burst = -1.0, first_crackle = -1.0;
  std::uint64_t checked = 0;
  for (int step = 0; step < int(7.0 / h); ++step) {
    before = snapshot();
    const std::uint64_t born_before = sw.world.emitted_count(crackle_sys);
    sw.world.advance(h);
    if (first_burst < 0.0 && sw.world.emitted_count(star_sys) > 0) first_burst = sw.world.time();
    const std::uint64_t born = sw.world.emitted_count(crackle_sys);
    if (born == born_before) continue;
    if (first_crackle < 0.0) first_crackle = sw.world.time();
    ASSERT_GT(first_burst, 0.0) << "crackle before the burst";
    // The stars that died in this step.
    const std::vector<Star> after = snapshot();
    std::vector<Star> died;
    for (const Star& s : before)
      if (std::none_of(after.begin(), after.end(), [&](const Star& a) { return a.id == s.id; })) died.push_back(s);
    ASSERT_FALSE(died.empty()) << "crackle at t = " << sw.world.time() << " with no star dying";
    const sim::ParticleView c = sw.world.particles(crackle_sys);
    for (std::size_t i = 0; i < c.count; ++i) {
      if (c.id[i] < born_before) continue;  // born earlier
      const sim::Vec3 x(c.position[3 * i], c.position[3 * i + 1], c.position[3 * i + 2]);
      double best = 1e9;
      for (const Star& s : died) {
        // flash: 5 cm sphere + at most 5 m/s of its own + the star's velocity, for under one step
        const double reach = 0.05 + (5.0 + 2.0 * s.v.norm()) * h + 1e-3;
        best = std::min(best, (x - s.x).norm() / reach);
      }
      EXPECT_LE(best, 1.0) << "flash id " << c.id[i] << " at t = " << sw.world.time() << " not at a dying star";
      ++checked;
    }
  }
  // Every star dies within 0.8..3.5 s of the burst (its lifetime); its trail sparks do not crackle.
  EXPECT_GE(first_crackle - first_burst, 0.8 - 2 * h);
  EXPECT_EQ(sw.world.emitted_count(crackle_sys), std::uint64_t(30 * stars));
  EXPECT_EQ(checked, std::uint64_t(30 * stars));
  EXPECT_GT(sw.world.emitted_count(star_sys), std::uint64_t(10 * stars)) << "trail sparks were made";

  // A fraction: about that share of the stars crackle.
  json half = fw;
  half["crackle"] = 0.5;
  half["stars"] = 400;
  auto sw_half = world_of(half, 1.0 / 60.0);
  for (int f = 0; f < 7 * 30; ++f) sw_half.world.advance(1.0 / 30);
  const double crackling = double(sw_half.world.emitted_count(sw_half.systems[system_named(sw_half, "fw/crackle0")])) / 30.0;
  EXPECT_NEAR(crackling, 200.0, 4 * std::sqrt(100.0)) << "binomial(400, 0.5) stars";

  // Off: no crackle system at all.
  json off = fw;
  off["crackle"] = 0;
  auto sw_off = world_of(off, h);
  for (std::size_t i = 0; i < sw_off.systems.size(); ++i)
    EXPECT_EQ(sw_off.world.definition(sw_off.systems[i]).name.find("crackle"), std::string::npos);
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
  e = errors_of({{"effect", "fireworks"}, {"crackle", 1.5}});
  EXPECT_NE(e.find("fx.json: /emitters/0/crackle: expected a number in [0, 1]"), std::string::npos) << e;
  e = errors_of({{"effect", "fireworks"}, {"crackle", true}});
  EXPECT_NE(e.find("fx.json: /emitters/0/crackle"), std::string::npos) << e;
}

TEST(EffectRecipes, BadSubEmittersAndStrobeNameTheirPointer) {
  auto errors_of = [](const json& emitters) {
    try {
      app::scene_from_json(json{{"emitters", emitters}}, "fx.json");
    } catch (const app::SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const json target = {{"name", "glitter"}, {"rate", 0}, {"render_style", "additive"}, {"strobe_hz", 10}};
  auto with = [&](const json& sub) {
    return json::array({{{"name", "stars"}, {"sub_emitters", json::array({sub})}}, target});
  };
  EXPECT_EQ(errors_of(with({{"emitter", "glitter"}, {"count", 5}})), "");
  std::string e = errors_of(with({{"emitter", "gliter"}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/sub_emitters/0/emitter: expected the name of an emitter"), std::string::npos) << e;
  e = errors_of(with({{"count", 5}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/sub_emitters/0: expected an \"emitter\""), std::string::npos) << e;
  e = errors_of(with({{"emitter", "glitter"}, {"trigger", "birth"}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/sub_emitters/0/trigger"), std::string::npos) << e;
  e = errors_of(with({{"emitter", "glitter"}, {"probability", 2}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/sub_emitters/0/probability: expected a number in [0, 1]"), std::string::npos) << e;
  e = errors_of(with({{"emitter", "glitter"}, {"count", 0}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/sub_emitters/0/count"), std::string::npos) << e;
  e = errors_of(json::array({{{"name", "a"}, {"sub_emitters", {{"emitter", "a"}}}}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/sub_emitters"), std::string::npos) << e;
  e = errors_of(json::array({{{"name", "a"}, {"strobe_hz", 5}}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/strobe_hz: expected \"strobe_hz\" and \"strobe_duty\" only with"), std::string::npos) << e;
  e = errors_of(json::array({{{"name", "a"}, {"render_style", "additive"}, {"strobe_duty", 0}}}));
  EXPECT_NE(e.find("fx.json: /emitters/0/strobe_duty"), std::string::npos) << e;
}
