// Knob physics of the effects layer against published measurements and closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "simreel/effects/effects.hpp"
#include "simreel/effects/physics.hpp"

using namespace simreel;

TEST(EffectsPhysics, DropMassIsWaterSphere) {
  // 2 mm drop: 1000 * pi * (2e-3)^3 / 6 = 4.18879e-6 kg.
  EXPECT_NEAR(effects::drop_mass(2.0), 4.18879e-6, 1e-10);
  EXPECT_NEAR(effects::drop_mass(4.0) / effects::drop_mass(2.0), 8.0, 1e-12);  // ~ D^3
  EXPECT_THROW(effects::drop_mass(0.0), std::invalid_argument);
}

TEST(EffectsPhysics, RaindropTerminalVelocityMatchesGunnKinzer) {
  // Gunn & Kinzer (1949) measured fall speeds (m/s) at sea level, by diameter (mm).
  const double d[] = {1.0, 2.0, 3.0, 4.0, 5.0};
  const double v[] = {4.03, 6.49, 8.06, 8.83, 9.09};
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(effects::raindrop_terminal_velocity(d[i]), v[i], 0.03 * v[i]) << d[i];
  EXPECT_THROW(effects::raindrop_terminal_velocity(0.1), std::invalid_argument);
  EXPECT_THROW(effects::raindrop_terminal_velocity(7.0), std::invalid_argument);
}

TEST(EffectsPhysics, DragGivesTheRequestedTerminalVelocity) {
  const double m = 4e-6, vt = 6.5, g = 9.81;
  const double kd = effects::drag_for_terminal_velocity(m, vt, g);
  EXPECT_NEAR(m * g / kd, vt, 1e-12);  // Coutinho §3.3.2: v_t = m g / k_d
}

TEST(EffectsPhysics, RainFluxAddsUpToTheIntensity) {
  // Water depth per hour = drops/m²/s * drop volume * 3600 s, in mm.
  for (double i : {1.0, 8.0, 50.0})
    for (double dmm : {0.5, 2.0, 5.0}) {
      const double n = effects::rain_drops_per_m2_s(i, dmm);
      const double vol = std::numbers::pi * std::pow(dmm * 1e-3, 3) / 6.0;
      EXPECT_NEAR(n * vol * 3600.0 * 1e3, i, 1e-9 * i);
    }
}

TEST(EffectsPhysics, LaunchSpeedReachesTheApex) {
  const double g = 9.81;
  for (double h : {0.5, 2.0, 20.0})
    for (double elev : {30.0, 60.0, 90.0}) {
      const double v0 = effects::launch_speed_for_apex(h, elev, g);
      const double vz = v0 * std::sin(elev * std::numbers::pi / 180.0);
      EXPECT_NEAR(vz * vz / (2 * g), h, 1e-9 * h);
    }
  EXPECT_THROW(effects::launch_speed_for_apex(1.0, 0.0), std::invalid_argument);
}

TEST(EffectsSpecs, SevenEffectsWithCheckedDefaults) {
  const auto& specs = effects::effect_specs();
  ASSERT_EQ(specs.size(), 7u);
  for (const char* name : {"smoke", "fire_smoke", "rain", "sprinkler", "jet", "explosion", "fireworks"})
    ASSERT_NE(effects::find_effect(name), nullptr) << name;
  for (const auto& e : specs) {
    EXPECT_FALSE(e.description.empty()) << e.name;
    EXPECT_NE(e.book.find("Coutinho"), std::string::npos) << e.name;
    for (const auto& k : e.knobs) {
      EXPECT_FALSE(k.description.empty()) << e.name << "." << k.name;
      // Every default lies inside the knob's own range, so a scene using defaults is valid.
      if (k.type == effects::KnobType::number || k.type == effects::KnobType::integer) {
        EXPECT_GE(k.default_value.get<double>(), k.min) << e.name << "." << k.name;
        EXPECT_LE(k.default_value.get<double>(), k.max) << e.name << "." << k.name;
      }
      if (k.type == effects::KnobType::choice) {
        bool found = false;
        for (const auto& c : k.choices) found = found || c == k.default_value.get<std::string>();
        EXPECT_TRUE(found) << e.name << "." << k.name;
      }
    }
  }
}
