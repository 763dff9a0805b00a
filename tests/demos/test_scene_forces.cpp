// Scene keys of forces and integrators (Coutinho §3.3, App. B): parsed into the definitions,
// and every bad value reported with file + JSON pointer; the CLI exits 2.
#include <gtest/gtest.h>

#include "cli_util.hpp"
#include "json_reader.hpp"
#include "scene.hpp"

namespace {

using simreel::app::json;
using simreel::app::scene_from_json;
using simreel::app::SceneError;
namespace sim = simreel::sim;

std::string errors_of(const json& doc) {
  try {
    (void)scene_from_json(doc, "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneForces, KeysReachTheDefinitions) {
  const auto doc = json::parse(R"({
    "simulation": {"threads": 2},
    "emitters": [
      {"name": "rope", "rate": 0, "integrator": "adaptive", "tolerance": 1e-5, "charge": 2e-6,
       "pair_forces": {"coulomb_K": 9e9, "cutoff": 0.5},
       "initial_particles": [{"position": [0, 0, 1], "mass": 0.1}, {"position": [0.2, 0, 1], "charge": -1e-6}],
       "springs": [{"a": 0, "b": 1, "stiffness": 50, "damping": 0.1, "rest_length": "initial"}]},
      {"name": "smoke"}],
    "force_fields": [
      {"type": "vortex", "region": {"shape": "sphere", "center": [0, 0, 1], "radius": 2}, "falloff": "quadratic",
       "strength": 3, "inward_strength": 0.5, "axis": [0, 0, 1], "systems": ["smoke"]},
      {"type": "curl_noise", "amplitude": 1, "frequency": 0.5, "scroll": [0, 0, 1], "drag": 1e-4}],
    "attractor_springs": [{"system": "rope", "ids": [1], "stiffness": 4, "anchor": [1, 0, 1]}]})");
  const auto s = scene_from_json(doc, "s.json");
  EXPECT_EQ(s.world.threads, 2);
  const auto& rope = s.emitters[0].system;
  EXPECT_EQ(rope.integrator, sim::Integrator::adaptive);
  EXPECT_DOUBLE_EQ(rope.tolerance, 1e-5);
  EXPECT_DOUBLE_EQ(rope.charge.mean, 2e-6);
  EXPECT_DOUBLE_EQ(rope.pair_forces.coulomb_K, 9e9);
  ASSERT_EQ(rope.initial_particles.size(), 2u);
  EXPECT_DOUBLE_EQ(rope.initial_particles[1].charge, -1e-6);
  ASSERT_EQ(rope.springs.size(), 1u);
  EXPECT_LT(rope.springs[0].rest_length, 0.0);  // "initial"
  ASSERT_EQ(s.force_fields.size(), 2u);
  EXPECT_EQ(s.force_fields[0].def.kind, sim::FieldKind::vortex);
  EXPECT_EQ(s.force_fields[0].def.falloff, sim::Falloff::quadratic);
  EXPECT_EQ(s.force_fields[0].systems, std::vector<std::string>{"smoke"});
  EXPECT_EQ(s.force_fields[1].def.kind, sim::FieldKind::curl_noise);
  ASSERT_EQ(s.attractor_springs.size(), 1u);
  EXPECT_EQ(s.attractor_springs[0].system, "rope");
  // And the world accepts it all.
  auto w = simreel::app::build_world(s);
  w.world.advance(1.0 / 30);
  EXPECT_EQ(w.world.particles(w.systems[0]).count, 2u);
}

TEST(SceneForces, BadValuesNamePointer) {
  const std::string e = errors_of(json::parse(R"({
    "emitters": [{"name": "a", "integrator": "verlet", "tolerance": 0,
                  "initial_particles": [{"position": [0, 0, 0]}], "springs": [{"a": 0, "b": 3}],
                  "pair_forces": {"cutoff": -1}}],
    "force_fields": [{"type": "vortex", "axis": [0, 0, 0], "strength": 1, "systems": ["b"]},
                     {"type": "uniform", "strength": 2}],
    "attractor_springs": [{"system": "a", "ids": [-1]}]})"));
  for (const char* want : {"s.json: /emitters/0/integrator: expected one of",
                           "s.json: /emitters/0/tolerance: expected a number",
                           "s.json: /emitters/0/springs/0",
                           "s.json: /emitters/0/pair_forces/cutoff",
                           "s.json: /force_fields/0/axis: expected a non-zero axis",
                           "s.json: /force_fields/0/systems/0: expected the name of an emitter (\"a\"), found \"b\"",
                           "s.json: /force_fields/1/strength",  // unknown for a uniform field
                           "s.json: /attractor_springs/0/ids/0: expected a particle id"})
    EXPECT_NE(e.find(want), std::string::npos) << want << "\n" << e;
}

TEST(SceneForces, CliExits2OnABadFieldValue) {
  simreel::test::TempDir d;
  simreel::test::write_file(d / "s.json", R"({"emitters": [{"name": "e"}],
      "force_fields": [{"type": "curl_noise", "frequency": -2}]})");
  const auto r = simreel::test::run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "s.json").string() + ": /force_fields/0/frequency: expected a number"),
            std::string::npos)
      << r.err;
}

}  // namespace
