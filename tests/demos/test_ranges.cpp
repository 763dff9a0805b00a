// Ranges written once (simreel/sim/ranges.hpp): for a handful of keys, the value just outside
// the range is rejected by the loader (SceneError naming the JSON pointer) and by the engine
// (std::invalid_argument naming the field), and the boundary value is accepted by both.
#include <gtest/gtest.h>

#include <charconv>
#include <functional>
#include <string>

#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/sim/ranges.hpp"

using simreel::app::build_world;
using simreel::app::json;
using simreel::app::Scene;
using simreel::app::scene_from_json;
using simreel::app::SceneError;
namespace sim = simreel::sim;

namespace {

/// The loader's message for `doc`, "" if it loads.
std::string loader_error(const std::string& doc) {
  try {
    (void)scene_from_json(json::parse(doc), "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

/// The engine's message when the scene (loaded from `doc`, which is valid) is registered after
/// `set` changed one definition field; "" if the engine accepts it.
std::string engine_error(const std::string& doc, const std::function<void(Scene&)>& set) {
  Scene scene = scene_from_json(json::parse(doc), "s.json");
  set(scene);
  try {
    sim::WorldDef def = scene.world;
    sim::World world(def);
    for (const auto& c : scene.colliders) {
      if (c.type == simreel::app::ColliderScene::Type::box) (void)world.add_box(c.box);
      if (c.type == simreel::app::ColliderScene::Type::plane) (void)world.add_plane(c.plane);
    }
    for (const auto& e : scene.emitters) (void)world.add_particle_system(e.system);
    for (const auto& c : scene.cloths) (void)world.add_cloth(c.def);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

struct Key {
  std::string name;
  std::string pointer;                 ///< JSON pointer in the loader's message
  std::string boundary_doc;            ///< scene with the key at its boundary
  std::string outside_doc;             ///< the same just outside
  std::function<void(Scene&)> at_boundary;  ///< sets the engine field to the boundary
  std::function<void(Scene&)> outside;      ///< sets the engine field just outside
  std::string field;                   ///< engine's name of the field
};

void check(const Key& k) {
  SCOPED_TRACE(k.name);
  EXPECT_EQ(loader_error(k.boundary_doc), "");
  const std::string loader = loader_error(k.outside_doc);
  EXPECT_NE(loader.find("s.json: " + k.pointer + ": expected"), std::string::npos) << loader;
  EXPECT_EQ(engine_error(k.boundary_doc, k.at_boundary), "");
  const std::string engine = engine_error(k.boundary_doc, k.outside);
  EXPECT_NE(engine.find(k.field), std::string::npos) << engine;
  EXPECT_NE(engine.find("must be"), std::string::npos) << engine;
}

}  // namespace

TEST(Ranges, RangeContainsItsBoundsAndRejectsNanAndInfinity) {
  constexpr sim::Range closed{0.0, 1.0};
  static_assert(closed.contains(0.0) && closed.contains(1.0) && !closed.contains(1.0000001));
  constexpr sim::Range open{0.0, 1.0, true};
  static_assert(!open.contains(0.0) && open.contains(1e-300));
  static_assert(!sim::ranges::kNonNegative.contains(sim::ranges::kInf));
  static_assert(sim::ranges::kClothMaxStrain.contains(sim::ranges::kInf));
  EXPECT_FALSE(closed.contains(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(sim::describe(sim::ranges::kEmitterRate), "in [0, 1e+09]");
  EXPECT_EQ(sim::describe(sim::ranges::kPositive), "> 0 and finite");
  EXPECT_EQ(sim::describe(sim::ranges::kHitSplitSizeFraction), "in (0, 1]");
}

TEST(Ranges, NumbersInMessagesKeepTheirMagnitudeAndHandedOnNumbersReadBackExactly) {
  // std::to_string(double) printed six fixed decimals: 1e-300 as "0.000000" (a time key "after"
  // an equal one), 1e300 as a 301-digit integer, and a sweep handed --fps 23.976023976 to its
  // children as 23.976024, so they rendered at another sampling time than the one asked for.
  EXPECT_EQ(sim::format_number(1e-300), "1e-300");
  EXPECT_EQ(sim::format_number(1e300), "1e+300");
  EXPECT_EQ(sim::format_number(0.1), "0.1");
  EXPECT_EQ(sim::format_number(23.976023976), "23.97602398");
  EXPECT_EQ(sim::format_number(-std::numeric_limits<double>::infinity()), "-inf");
  for (const double x : {23.976023976, 1.0 / 3.0, 1e-300, 5e-324, 1.7976931348623157e308, -0.1, 60.0, 0.0}) {
    const std::string t = sim::exact_number(x);
    double back = -1.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), back);
    EXPECT_TRUE(ec == std::errc() && end == t.data() + t.size()) << t;
    EXPECT_EQ(back, x) << t;
    EXPECT_LE(t.size(), 24u) << t;
  }
  EXPECT_EQ(sim::exact_number(23.976023976), "23.976023976");
  EXPECT_EQ(sim::exact_number(60.0), "60");
}

TEST(Ranges, EmitterRateCappedAt1e9ByLoaderAndEngine) {
  check({"rate", "/emitters/0/rate", R"({"emitters":[{"rate":1e9}]})", R"({"emitters":[{"rate":2e9}]})",
         [](Scene& s) { s.emitters[0].system.emitter.rate = 1e9; },
         [](Scene& s) { s.emitters[0].system.emitter.rate = 2e9; }, "emitter.rate"});
  const std::string engine =
      engine_error(R"({"emitters":[{}]})", [](Scene& s) { s.emitters[0].system.emitter.rate = 2e9; });
  EXPECT_NE(engine.find("emitter.rate must be in [0, 1e+09] (got 2e+09)"), std::string::npos) << engine;
}

TEST(Ranges, SplitDepthAndDelayStepsSharedBounds) {
  check({"split.depth", "/emitters/0/split/depth", R"({"emitters":[{"split":{"depth":32}}]})",
         R"({"emitters":[{"split":{"depth":33}}]})", [](Scene& s) { s.emitters[0].system.emitter.split.depth = 32; },
         [](Scene& s) { s.emitters[0].system.emitter.split.depth = 33; }, "split.depth"});
  check({"split.delay_steps", "/emitters/0/split/delay_steps",
         R"({"emitters":[{"split":{"delay_steps":1000000}}]})", R"({"emitters":[{"split":{"delay_steps":1000001}}]})",
         [](Scene& s) { s.emitters[0].system.emitter.split.delay_steps = 1'000'000; },
         [](Scene& s) { s.emitters[0].system.emitter.split.delay_steps = 1'000'001; }, "split.delay_steps"});
}

TEST(Ranges, MaterialRestitutionAndHitSplitSizeFraction) {
  check({"restitution", "/colliders/0/restitution", R"({"colliders":[{"type":"plane","restitution":1}]})",
         R"({"colliders":[{"type":"plane","restitution":1.01}]})",
         [](Scene& s) { s.colliders[0].plane.material.restitution = 1.0; },
         [](Scene& s) { s.colliders[0].plane.material.restitution = 1.01; }, "PlaneDef.material.restitution"});
  // (0, 1]: zero is outside (open bound), one is inside.
  check({"split.size_fraction", "/colliders/0/split/size_fraction",
         R"({"colliders":[{"type":"box","split":{"size_fraction":1}}]})",
         R"({"colliders":[{"type":"box","split":{"size_fraction":0}}]})",
         [](Scene& s) { s.colliders[0].box.material.split.size_fraction = 1.0; },
         [](Scene& s) { s.colliders[0].box.material.split.size_fraction = 0.0; },
         "BoxDef.material.split.size_fraction"});
}

TEST(Ranges, ClothGridCappedAt1024ByLoaderAndEngine) {
  check({"cloth rows", "/cloths/0/rows", R"({"cloths":[{"rows":1024,"columns":2}]})",
         R"({"cloths":[{"rows":1025,"columns":2}]})", [](Scene& s) { s.cloths[0].def.rows = 1024; },
         [](Scene& s) { s.cloths[0].def.rows = 1025; }, "ClothDef.rows"});
}

TEST(Ranges, WorldMaxStepAtMostOneSecond) {
  check({"max_step", "/simulation/max_step", R"({"simulation":{"max_step":1}})",
         R"({"simulation":{"max_step":1.5}})", [](Scene& s) { s.world.max_step = 1.0; },
         [](Scene& s) { s.world.max_step = 1.5; }, "WorldDef.max_step"});
}

TEST(Ranges, KeyframeTimesStartAtZero) {
  check({"path time", "/colliders/0/path/keys/0/time",
         R"({"colliders":[{"type":"box","path":{"keys":[{"time":0},{"time":1,"position":[1,0,0]}]}}]})",
         R"({"colliders":[{"type":"box","path":{"keys":[{"time":-0.1},{"time":1,"position":[1,0,0]}]}}]})",
         [](Scene& s) { s.colliders[0].box.path.keys[0].time = 0.0; },
         [](Scene& s) { s.colliders[0].box.path.keys[0].time = -0.1; }, "BoxDef.path.keys[0].time"});
}
