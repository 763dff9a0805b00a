// Jet knobs (Coutinho §3.9.1): start speed from apex height, checked against the engine.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "simreel/effects/jets.hpp"
#include "simreel/sim/world.hpp"

using namespace simreel;

TEST(Jets, SpeedAndApexAreInverse) {
  for (double h : {0.5, 2.0, 10.0}) {
    const double v = effects::vertical_jet_speed(h);
    EXPECT_NEAR(v, std::sqrt(2 * 9.81 * h), 1e-12);
    EXPECT_NEAR(effects::apex_height(v, 90.0), h, 1e-9);
    EXPECT_NEAR(effects::apex_height(v, 30.0), h * 0.25, 1e-9);  // sin²(30°) = 1/4
  }
  EXPECT_THROW(effects::vertical_jet_speed(-1.0), std::invalid_argument);
  EXPECT_THROW(effects::vertical_jet_speed(1.0, 0.0), std::invalid_argument);
}

TEST(Jets, SimulatedVerticalJetReachesTheRequestedHeight) {
  const double h = 2.0;
  sim::World world(sim::WorldDef{1.0 / 1000.0, 1, 0.05});
  sim::ParticleSystemDef def;
  def.emitter.rate = 1000.0;
  def.emitter.stop_time = 0.0015;  // a single particle
  def.emitter.start_speed = {effects::vertical_jet_speed(h), 0.0, 0.0};
  def.emitter.lifetime = {5.0, 0.0, 0.0};
  def.collide = false;
  const auto ps = world.add_particle_system(def);
  double apex = -1e9;
  for (int i = 0; i < 1000; ++i) {
    world.advance(1.0 / 1000.0);
    const auto v = world.particles(ps);
    if (v.count) apex = std::max(apex, double(v.position[2]));
  }
  ASSERT_EQ(world.emitted_count(ps), 1u);
  EXPECT_NEAR(apex, h, 0.01 * h);
}
