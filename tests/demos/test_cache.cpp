// The simulation cache (issue 18, docs/cache.md): World::save_state / load_state continue a
// world bit-identically; `simreel bake` + `simreel render --cache` give the PNG bytes of a
// straight render; a bake killed (SIGKILL) at random moments and resumed ends byte-identical to
// an uninterrupted one; a cache of another scene, overrides, seed or build, or a truncated or
// corrupt frame file, is refused with exit code 2 naming the file and what differs.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <ostream>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "cli_util.hpp"
#include "scene.hpp"
#include "simreel/sim/joint.hpp"
#include "simreel/sim/world.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using simreel::app::build_world;
using simreel::app::load_scene;
using simreel::app::Scene;
using simreel::app::SceneWorld;
using simreel::test::run_simreel;
using simreel::test::slurp;
using simreel::test::TempDir;

fs::path scene_path(const std::string& name) {
  return fs::path(SIMREEL_SOURCE_DIR) / "demos" / "scenes" / (name + ".json");
}

void advance(SceneWorld& sw, const Scene& scene, int frames) {
  for (int f = 0; f < frames; ++f) sw.world.advance(1.0 / scene.fps);
}

struct Split {
  const char* scene;
  int save_at;  ///< frame whose state is saved and restored
  int end;      ///< frames simulated in all
};

void PrintTo(const Split& s, std::ostream* os) {
  *os << s.scene << " saved at frame " << s.save_at << ", continued to " << s.end;
}

class StateRoundTrip : public ::testing::TestWithParam<Split> {};

// A world restored from the state of frame k and advanced to frame n equals, in every byte of
// its state, the world advanced straight to n. Scenes: particles with collisions and splashes
// (fountain), particle-particle contacts with warm starts (pour), cloth with the implicit
// solver's warm start (flag), bursts and fields (explosion), dynamic bodies hit by a jet
// (jet_crates), bodies settling into contact and sleep (tumble, saved after they sleep) and
// cloth folding onto itself over a table (tablecloth: the contacts' tree is rebuilt at every
// step's start and refitted after, so it is a function of the state, not of its history).
TEST_P(StateRoundTrip, RestoredWorldContinuesBitIdentically) {
  const Split p = GetParam();
  const Scene scene = load_scene(scene_path(p.scene));
  SceneWorld straight = build_world(scene);
  advance(straight, scene, p.end);

  SceneWorld first = build_world(scene);
  advance(first, scene, p.save_at);
  std::string saved;
  first.world.save_state(saved);

  SceneWorld restored = build_world(scene);
  restored.world.load_state(saved);
  EXPECT_EQ(restored.world.state_hash(), first.world.state_hash());
  std::string again;
  restored.world.save_state(again);
  EXPECT_TRUE(again == saved) << "save(load(s)) != s";
  advance(restored, scene, p.end - p.save_at);

  EXPECT_EQ(restored.world.state_hash(), straight.world.state_hash()) << p.scene;
  std::string a, b;
  straight.world.save_state(a);
  restored.world.save_state(b);
  EXPECT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b) << p.scene << ": the saved states differ after continuing";
}

INSTANTIATE_TEST_SUITE_P(Scenes, StateRoundTrip,
                         ::testing::Values(Split{"fountain", 20, 45}, Split{"pour", 24, 34}, Split{"flag", 15, 40},
                                           Split{"explosion", 6, 30}, Split{"jet_crates", 30, 55},
                                           Split{"tumble", 75, 100}, Split{"tablecloth", 34, 40}),
                         [](const auto& info) { return std::string(info.param.scene); });

/// A chain of four boxes hung from the world by spherical joints, released sideways so it
/// swings into the ground; the second link turns a motor-driven hinge box; the last joint breaks
/// at a low force during the swing (Coutinho Ch. 5).
struct JointWorld {
  simreel::sim::World world;
  std::vector<simreel::sim::JointHandle> joints;
  JointWorld() {
    using namespace simreel::sim;
    BodyDef ground;
    ground.shapes = {ShapeDef::plane()};
    world.add_body(ground);
    BodyHandle prev;  // null: the world
    for (int i = 0; i < 4; ++i) {
      BodyDef b;
      b.type = BodyType::dynamic;
      b.pose.translation = Vec3(0.3 * (i + 1), 0.0, 1.2);
      b.shapes = {ShapeDef::box(Vec3(0.1, 0.06, 0.06))};
      const BodyHandle h = world.add_body(b);
      JointDef j;
      j.type = i == 1 ? JointType::hinge : JointType::spherical;
      j.body_a = prev;
      j.body_b = h;
      j.anchor = Vec3(0.3 * i + 0.15, 0.0, 1.2);
      j.axis = Vec3::UnitY();
      j.motor_enabled = i == 1;
      j.motor_speed = 2.0;
      j.max_motor_torque = 5.0;
      j.break_force = i == 3 ? 40.0 : std::numeric_limits<double>::infinity();
      joints.push_back(world.add_joint(j));
      prev = h;
    }
  }
};

// Joints: a world restored mid-swing continues bit-identically, from before the last joint
// breaks (the break included) and from after it (it stays broken).
TEST(StateRoundTrip, JointedChainContinuesBitIdentically) {
  constexpr double dt = 1.0 / 30.0;
  constexpr int kEnd = 60;
  JointWorld straight, first;
  for (int f = 0; f < kEnd; ++f) straight.world.advance(dt);
  ASSERT_TRUE(straight.world.joint_state(straight.joints[3]).broken) << "the test needs the last joint to break";
  int k = 0;  // the frame the last joint is first seen broken
  for (; k < kEnd && !first.world.joint_state(first.joints[3]).broken; ++k) first.world.advance(dt);
  ASSERT_GT(k, 3);
  ASSERT_LT(k + 3, kEnd);
  std::string a;
  straight.world.save_state(a);
  for (const int save_at : {k - 2, k + 2}) {
    JointWorld replay, restored;
    for (int f = 0; f < save_at; ++f) replay.world.advance(dt);
    EXPECT_EQ(replay.world.joint_state(replay.joints[3]).broken, save_at > k);
    std::string saved;
    replay.world.save_state(saved);
    restored.world.load_state(saved);
    for (int f = save_at; f < kEnd; ++f) restored.world.advance(dt);
    EXPECT_TRUE(restored.world.joint_state(restored.joints[3]).broken);
    std::string b;
    restored.world.save_state(b);
    EXPECT_TRUE(a == b) << "saved at frame " << save_at << ": the states differ after continuing";
    for (std::size_t i = 0; i < 4; ++i) {
      const auto ra = straight.world.joint_state(straight.joints[i]);
      const auto rb = restored.world.joint_state(restored.joints[i]);
      EXPECT_EQ(ra.force, rb.force) << "joint " << i << ", saved at frame " << save_at;
      EXPECT_EQ(ra.angle, rb.angle) << "joint " << i << ", saved at frame " << save_at;
    }
  }
}

// The tumble split above really saves sleeping bodies and live contacts (else it proves less).
TEST(StateRoundTrip, TumbleSplitHoldsSleepingBodiesAndContacts) {
  const Scene scene = load_scene(scene_path("tumble"));
  SceneWorld sw = build_world(scene);
  advance(sw, scene, 75);
  int asleep = 0, dynamic = 0;
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    if (!scene.colliders[i].dynamic.enabled) continue;
    ++dynamic;
    asleep += sw.world.is_awake(sw.colliders[i]) ? 0 : 1;
  }
  EXPECT_GT(dynamic, 0);
  EXPECT_GT(asleep, 0) << "no body sleeps at frame 75";
  EXPECT_LT(asleep, dynamic) << "every body sleeps at frame 75: no awake contact is saved";
}

TEST(StateRoundTrip, StateOfAnotherSceneIsRefused) {
  const Scene fountain = load_scene(scene_path("fountain"));
  const Scene flag = load_scene(scene_path("flag"));
  SceneWorld a = build_world(fountain);
  std::string s;
  a.world.save_state(s);
  SceneWorld b = build_world(flag);
  EXPECT_THROW(b.world.load_state(s), simreel::sim::StateError);
  SceneWorld c = build_world(fountain);
  EXPECT_THROW(c.world.load_state(std::string_view(s).substr(0, s.size() - 3)), simreel::sim::StateError);
  EXPECT_THROW(c.world.load_state(std::string_view(s).substr(0, 10)), simreel::sim::StateError);
}

// A corrupt record count (the checksum recomputed over it, as a hand-made file would have) is
// refused from the bytes the section has left, before anything is allocated for it: 2^32
// contact manifolds asked for a terabyte, and `bake --resume` ended in std::bad_alloc (exit 1).
TEST(StateRoundTrip, RecordCountBeyondTheSectionIsRefusedBeforeAllocating) {
  const Scene tumble = load_scene(scene_path("tumble"));
  SceneWorld a = build_world(tumble);
  for (int i = 0; i < 40; ++i) a.world.advance(1.0 / 60.0);  // bodies on the ground: manifolds
  std::string s;
  a.world.save_state(s);
  const std::size_t tag = s.find("CONT");
  ASSERT_NE(tag, std::string::npos);
  std::uint64_t section = 0, manifolds = 0;
  std::memcpy(&section, s.data() + tag + 4, 8);
  std::memcpy(&manifolds, s.data() + tag + 12, 8);
  ASSERT_GT(manifolds, 0u) << "tumble's bodies should touch something after 40 frames";
  for (const std::uint64_t bad : {std::uint64_t{1} << 32, std::uint64_t{1} << 62, section}) {
    std::string c = s;
    std::memcpy(c.data() + tag + 12, &bad, 8);
    SceneWorld b = build_world(tumble);
    try {
      b.world.load_state(c);
      ADD_FAILURE() << bad << " manifolds were accepted";
    } catch (const simreel::sim::StateError& e) {
      EXPECT_NE(std::string(e.what()).find(std::to_string(bad) + " contact manifolds declared, the "),
                std::string::npos)
          << e.what();
    }
  }
  SceneWorld b = build_world(tumble);
  EXPECT_NO_THROW(b.world.load_state(s));
}

/// The state of `scene` after `frames` frames with the 8-byte double (or 4-byte float) at `offset`
/// bytes after the first occurrence of section tag `tag` set to `value`.
std::string state_with(const Scene& scene, int frames, const char* tag, std::size_t offset, double value,
                       bool as_float) {
  SceneWorld a = build_world(scene);
  for (int i = 0; i < frames; ++i) a.world.advance(1.0 / 60.0);
  std::string s;
  a.world.save_state(s);
  const std::size_t at = s.find(tag);
  EXPECT_NE(at, std::string::npos) << tag;
  if (at == std::string::npos) return s;
  if (as_float) {
    const float f = float(value);
    std::memcpy(s.data() + at + offset, &f, sizeof f);
  } else {
    std::memcpy(s.data() + at + offset, &value, sizeof value);
  }
  return s;
}

// A state whose bytes are intact (its cache checksum recomputed) but whose values no step could
// have written: NaN, inf, a particle beyond simulation.max_distance. Each is refused at load with
// the quantity named, where it used to load and stop the run one step later as "simulation
// diverged" (exit 1). Offsets: a section is its tag (4 bytes) and size (8), then its fields
// (state_snapshot.cpp).
TEST(StateRoundTrip, NonFiniteOrOutOfBoundsValuesAreRefusedAtLoad) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* scene;
    int frames;
    const char* tag;
    std::size_t offset;
    double value;
    bool as_float;
    const char* names;
  };
  const Case cases[] = {
      {"tumble", 5, "WRLD", 12, nan, false, "the world time is not finite"},
      // BODY: body count (8), the first body's motion type (1), its position.
      {"tumble", 5, "BODY", 21, nan, false, "position is not finite"},
      // RIGD: rigid count (8), the positions' count (8), the first position.
      {"tumble", 5, "RIGD", 28, inf, false, "rigid positions: value 0 of"},
      // The first orientation's w (after the positions: n Vec3 and the orientations' count), and a
      // velocity far above light's (the step's own divergence bound): finite, yet no step writes
      // them.
      {"tumble", 5, "RIGD", 28 + 6 * 24 + 8 + 24, 3.0, false, "is not a unit quaternion"},
      {"tumble", 5, "RIGD", 28 + 6 * 24 + 8 + 6 * 32 + 8, 1e12, false, "faster than light"},
      // The relations the step keeps between the arrays: body 0's angular momentum L.x (ω is no
      // longer I_w⁻¹ L) and its body inertia I_b(0,0) (I_b⁻¹ no longer its inverse).
      {"tumble", 5, "RIGD", 532, 7.5, false, "angular velocity is not I_w^-1 L"},
      {"tumble", 5, "RIGD", 948, 1e3, false, "inverse inertia is not the inverse of its inertia"},
      {"tumble", 5, "RIGD", 948 + 8, 1e3, false, "inertia is not symmetric positive definite"},
      // SHAP: shape count (8), the first shape's type (1) and point (24), its normal (fountain's
      // ground plane: (0, 0, 1)).
      {"fountain", 30, "SHAP", 45, 0.5, false, "shape 0: the normal is not a unit vector"},
      // PSYS: system count (8), particle count (8), the positions' count (8), the first position.
      {"fountain", 30, "PSYS", 36, nan, true, "particle positions: value 0 of"},
      {"fountain", 30, "PSYS", 36, 2.0e7, true, "is beyond simulation.max_distance"},
      // CLTH: cloth count (8), vertex count (8), the positions' count (8), the first position.
      {"flag", 5, "CLTH", 36, -inf, false, "positions: value 0 of"},
      {"flag", 5, "CLTH", 36, -2.0e7, false, "cloth 'flag': vertex 0 is beyond simulation.max_distance"},
  };
  {  // the RIGD offsets below assume tumble's six rigid bodies
    SceneWorld a = build_world(load_scene(scene_path("tumble")));
    std::string s;
    a.world.save_state(s);
    std::uint64_t rigid = 0;
    std::memcpy(&rigid, s.data() + s.find("RIGD") + 12, 8);
    ASSERT_EQ(rigid, 6u);
  }
  for (const Case& c : cases) {
    const Scene scene = load_scene(scene_path(c.scene));
    const std::string bad = state_with(scene, c.frames, c.tag, c.offset, c.value, c.as_float);
    SceneWorld b = build_world(scene);
    try {
      b.world.load_state(bad);
      ADD_FAILURE() << c.scene << " " << c.tag << "+" << c.offset << " = " << c.value << " was accepted";
    } catch (const simreel::sim::StateError& e) {
      EXPECT_NE(std::string(e.what()).find(c.names), std::string::npos) << c.scene << ": " << e.what();
    }
  }
}

// The load checks refuse no state a step writes: every frame's state of the scenes with bodies,
// joints, contacts, sleep and cloth loads (a check too tight would refuse a user's cache). The
// scene list, the frame count and the stride are overridable for a longer sweep
// (SIMREEL_STATE_SWEEP="scene,scene:frames").
TEST(StateRoundTrip, EveryStateAStepWritesPassesTheLoadChecks) {
  std::vector<std::string> scenes = {"tumble", "dominoes", "chandelier", "rope_bridge", "ring_toss",
                                     "newtons_cradle", "jet_crates", "flag"};
  int frames = 90;
  if (const char* e = std::getenv("SIMREEL_STATE_SWEEP")) {
    std::string v = e;
    if (const auto colon = v.find(':'); colon != std::string::npos) {
      frames = std::stoi(v.substr(colon + 1));
      v = v.substr(0, colon);
    }
    scenes.clear();
    for (std::size_t at = 0; at <= v.size();) {
      const std::size_t comma = std::min(v.find(',', at), v.size());
      scenes.push_back(v.substr(at, comma - at));
      at = comma + 1;
    }
  }
  for (const std::string& name : scenes) {
    const Scene scene = load_scene(scene_path(name.c_str()));
    SceneWorld a = build_world(scene), b = build_world(scene);
    std::string s;
    for (int f = 0; f < frames; ++f) {
      a.world.advance(1.0 / 60.0);
      a.world.save_state(s);
      try {
        b.world.load_state(s);
      } catch (const simreel::sim::StateError& e) {
        ADD_FAILURE() << name << " frame " << f + 1 << ": " << e.what();
        break;
      }
    }
  }
}

// Bodies whose inertia is ill-conditioned (a 6 m steel needle 0.1 mm thick, tumbling onto the
// ground, inertia condition ~10^9; a 2 m rod 2 mm thick spinning on a spherical joint, whose
// solver sets L = I_w ω): the inverse inertia and ω = I_w⁻¹ L hold only to the condition number
// times the rounding, and their states must load too. (The checks allow for that; these bodies,
// about the most slender the engine steps, load even without the allowance.)
TEST(StateRoundTrip, IllConditionedInertiaStatesPassTheLoadChecks) {
  TempDir tmp;
  const fs::path file = tmp / "needle.json";
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs(R"({"fps": 30, "colliders": [{"type": "plane", "name": "ground"}],
 "bodies": [
  {"name": "needle", "shape": "capsule", "radius": 0.00005, "half_height": 3.0, "density": 7800,
   "position": [0, 0, 4], "rotation_deg": [35, 20, 0], "angular_velocity_deg": [40, 300, 10]},
  {"name": "rod", "shape": "capsule", "radius": 0.001, "half_height": 1.0, "density": 7800,
   "position": [2, 0, 3], "angular_velocity_deg": [0, 200, 50]}],
 "joints": [{"type": "spherical", "name": "hang", "body_a": "world", "body_b": "rod", "anchor": [2, 0, 4]}]})",
             f);
  std::fclose(f);
  const Scene scene = load_scene(file);
  SceneWorld a = build_world(scene), b = build_world(scene);
  std::string s;
  // The needle (inertia ratio 1e9) spins up neither in free flight (integrate.cpp's split
  // rotation) nor when the sweep stops it at its time of impact (body_ccd.cpp turns its angular
  // momentum back with its pose; kept in the world frame, it read as a spin about the axis that
  // made the run diverge at 1.3 s): every state of the 3 s is checked.
  int checked = 0;
  for (int frame = 1; frame <= 90; ++frame) {
    try {
      a.world.advance(1.0 / 30.0);
    } catch (const simreel::sim::NonFiniteState&) {
      break;
    }
    ++checked;
    a.world.save_state(s);
    try {
      b.world.load_state(s);
    } catch (const simreel::sim::StateError& e) {
      ADD_FAILURE() << "frame " << frame << ": " << e.what();
      break;
    }
  }
  std::printf("[ figures  ] needle states checked: %d of 90 frames\n", checked);
  EXPECT_EQ(checked, 90);  // measured: 90 (39 before the sweep kept the spin, 20 before the split rotation)
}

/// Every PNG of `dir`, by name.
std::vector<std::pair<std::string, std::string>> pngs(const fs::path& dir) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".png") out.emplace_back(e.path().filename().string(), slurp(e.path()));
  std::sort(out.begin(), out.end());
  return out;
}

class RenderFromCache : public ::testing::TestWithParam<const char*> {};

// bake + render --cache of a range == the same frames of one straight render of the whole video.
TEST_P(RenderFromCache, PngBytesEqualAStraightRender) {
  const std::string scene = scene_path(GetParam()).string();
  TempDir tmp;
  const std::string common = " --frames 14 --size 160x90 -q";
  const auto straight = run_simreel("render " + scene + common + " -o " + (tmp / "straight").string());
  ASSERT_EQ(straight.code, 0) << straight.err;
  const auto bake = run_simreel("bake " + scene + " --frames 14 -q --cache " + (tmp / "cache").string());
  ASSERT_EQ(bake.code, 0) << bake.err;
  const auto ranged = run_simreel("render " + scene + " --frames 9:14 --size 160x90 -q --cache " +
                                  (tmp / "cache").string() + " -o " + (tmp / "ranged").string());
  ASSERT_EQ(ranged.code, 0) << ranged.err;
  const auto all = pngs(tmp / "straight");
  const auto part = pngs(tmp / "ranged");
  ASSERT_EQ(all.size(), 14u);
  ASSERT_EQ(part.size(), 5u);
  for (const auto& [name, bytes] : part) {
    const auto it = std::find_if(all.begin(), all.end(), [&](const auto& x) { return x.first == name; });
    ASSERT_NE(it, all.end()) << name;
    EXPECT_TRUE(it->second == bytes) << GetParam() << ": " << name << " differs from the straight render";
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, RenderFromCache,
                         ::testing::Values("fountain", "pour", "flag", "explosion", "tumble"));

/// Every file under `dir` (relative path -> bytes).
std::vector<std::pair<std::string, std::string>> tree(const fs::path& dir) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out.emplace_back(fs::relative(e.path(), dir).string(), slurp(e.path()));
  std::sort(out.begin(), out.end());
  return out;
}

/// Starts simreel with `args`, kills it with SIGKILL after `delay`; true if it was still running.
bool run_and_kill(const std::vector<std::string>& args, std::chrono::microseconds delay) {
  std::vector<std::string> full{SIMREEL_BIN};
  full.insert(full.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : full) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, SIMREEL_BIN, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return false;
  std::this_thread::sleep_for(delay);
  const bool running = waitpid(pid, nullptr, WNOHANG) == 0;
  if (running) kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return running;
}

// A bake killed with SIGKILL at 10 random moments, each time resumed with --resume, then
// finished, holds exactly the files (manifest, states, PLY) of an uninterrupted bake. Each run
// is killed within its first tenth of a full bake (start-up, part-written files and renames
// included), so the ten kills land across the whole bake.
TEST(BakeResume, KilledTenTimesAndResumedEqualsUninterrupted) {
  TempDir tmp;
  const std::string scene = scene_path("fountain").string();
  const auto t0 = std::chrono::steady_clock::now();
  const auto ref = run_simreel("bake " + scene + " --frames 90 --ply -q --cache " + (tmp / "ref").string());
  ASSERT_EQ(ref.code, 0) << ref.err;
  const auto full = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0);

  const std::vector<std::string> args{"bake", scene, "--frames", "90", "--ply", "-q", "--resume", "--cache",
                                      (tmp / "killed").string()};
  std::mt19937 rng(18);
  std::uniform_int_distribution<long long> when(full.count() / 50, full.count() / 10);
  int killed = 0;
  for (int k = 0; k < 10; ++k) killed += run_and_kill(args, std::chrono::microseconds(when(rng))) ? 1 : 0;
  EXPECT_GE(killed, 8) << "too few kills landed while the bake ran";
  // On a loaded machine start-up can take longer than the reference run suggested, and all ten
  // kills land before the first frame is baked: kill later (the window doubles, up to half a
  // bake) until one does, so the resume below still starts from baked frames.
  const auto baked_frames = [&] {
    int n = 0;
    if (fs::exists(tmp / "killed" / "state"))
      for (const auto& e : fs::directory_iterator(tmp / "killed" / "state")) n += e.path().extension() == ".state";
    return n;
  };
  for (long long scale = 2; baked_frames() == 0 && scale <= 32; scale *= 2) {
    const long long us = full.count();
    std::uniform_int_distribution<long long> later(us * scale / 50, std::min(us * scale / 10, us / 2));
    killed += run_and_kill(args, std::chrono::microseconds(later(rng))) ? 1 : 0;
  }
  ASSERT_TRUE(fs::exists(tmp / "killed" / "manifest.json"));
  EXPECT_NE(slurp(tmp / "killed" / "manifest.json").find("\"complete\": false"), std::string::npos)
      << "the killed bake finished before the last run";
  int baked = 0;
  for (const auto& e : fs::directory_iterator(tmp / "killed" / "state")) baked += e.path().extension() == ".state";
  EXPECT_GT(baked, 0) << "no kill landed after a frame was baked";
  std::printf("10 runs killed (%d while running) left %d of 90 frames; the last run resumes\n", killed, baked);
  std::string cmd = "bake " + scene + " --frames 90 --ply -q --resume --cache " + (tmp / "killed").string();
  const auto last = run_simreel(cmd);
  ASSERT_EQ(last.code, 0) << last.err;

  const auto a = tree(tmp / "ref");
  const auto b = tree(tmp / "killed");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].first, b[i].first);
    EXPECT_TRUE(a[i].second == b[i].second) << a[i].first << " differs";
  }
}

class CacheRefused : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    scene_ = (dir_->path / "fountain.json").string();
    fs::copy_file(scene_path("fountain"), scene_);
    const auto r = run_simreel("bake " + scene_ + " --frames 6 -q --cache " + cache());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string cache() { return (dir_->path / "cache").string(); }
  static simreel::test::RunResult render(const std::string& extra) {
    return run_simreel("render " + scene_ + " --frames 2:6 --size 64x36 -q --cache " + cache() + " -o " +
                       (dir_->path / "out").string() + extra);
  }
  static TempDir* dir_;
  static std::string scene_;
};
TempDir* CacheRefused::dir_ = nullptr;
std::string CacheRefused::scene_;

TEST_F(CacheRefused, MatchingCacheRenders) {
  const auto r = render("");
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST_F(CacheRefused, OtherOverridesSeedOrFps) {
  auto r = render(" --set /emitters/0/rate=100");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("manifest.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("overrides [] differ from --set [/emitters/0/rate=100]"), std::string::npos) << r.err;
  r = render(" --seed 99");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("seed"), std::string::npos) << r.err;
  r = render(" --fps 25");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("fps 30 differs from 25"), std::string::npos) << r.err;
  // Rates that agree to six digits are told apart (the message printed "fps 30 differs from 30").
  r = render(" --fps 30.0000001");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("fps 30 differs from 30.0000001"), std::string::npos) << r.err;
}

TEST_F(CacheRefused, FramesBeyondTheBake) {
  const auto r = run_simreel("render " + scene_ + " --frames 2:9 --size 64x36 -q --cache " + cache() + " -o " +
                             (dir_->path / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("the cache holds frames 0..5"), std::string::npos) << r.err;
}

TEST_F(CacheRefused, EditedSceneFileOrOtherBuild) {
  TempDir tmp;
  fs::copy(cache(), tmp / "c", fs::copy_options::recursive);
  const std::string edited = (tmp / "fountain.json").string();
  simreel::test::write_file(edited, slurp(scene_) + "\n");
  auto r = run_simreel("render " + edited + " --frames 2:6 --size 64x36 -q --cache " + (tmp / "c").string() +
                       " -o " + (tmp / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("scene hash"), std::string::npos) << r.err;
  // A manifest from another build.
  std::string m = slurp(tmp / "c" / "manifest.json");
  const auto at = m.find("\"simreel_version\": \"");
  ASSERT_NE(at, std::string::npos);
  m.insert(at + 20, "0.0.0-other+");
  simreel::test::write_file(tmp / "c" / "manifest.json", m);
  r = run_simreel("render " + scene_ + " --frames 2:6 --size 64x36 -q --cache " + (tmp / "c").string() + " -o " +
                  (tmp / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("baked by simreel 0.0.0-other+"), std::string::npos) << r.err;
}

TEST_F(CacheRefused, TruncatedOrCorruptFrame) {
  TempDir tmp;
  fs::copy(cache(), tmp / "c", fs::copy_options::recursive);
  const fs::path f3 = tmp / "c" / "state" / "frame_00003.state";
  const std::string bytes = slurp(f3);
  simreel::test::write_file(f3, bytes.substr(0, bytes.size() / 2));
  auto r = run_simreel("render " + scene_ + " --frames 2:6 --size 64x36 -q --cache " + (tmp / "c").string() + " -o " +
                       (tmp / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("frame_00003.state: truncated"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "out" / "frame_00002.png")) << "nothing is written from a bad cache";
  std::string flipped = bytes;
  flipped[flipped.size() - 5] ^= 0x10;
  simreel::test::write_file(f3, flipped);
  r = run_simreel("render " + scene_ + " --frames 2:6 --size 64x36 -q --cache " + (tmp / "c").string() + " -o " +
                  (tmp / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("frame_00003.state: corrupt"), std::string::npos) << r.err;
  fs::remove(f3);
  r = run_simreel("render " + scene_ + " --frames 2:6 --size 64x36 -q --cache " + (tmp / "c").string() + " -o " +
                  (tmp / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("frame_00003.state: missing"), std::string::npos) << r.err;
}

TEST_F(CacheRefused, HandEditedManifestOrAFifoFrameIsNamedNotCastOrWaitedOn) {
  // "frames": 1e12 was cast to int ("the cache holds frames 0..-727379969"), "seed": -1 read as
  // 2^64 - 1, a string gave nlohmann's message without the key, and a FIFO in place of the
  // manifest or a frame blocked `render --cache` and `bake --resume` forever.
  TempDir tmp;
  const std::string c = (tmp / "c").string();
  const std::string manifest = slurp(fs::path(cache()) / "manifest.json");
  const auto with = [&](const std::string& key, const std::string& value) {
    fs::remove_all(tmp / "c");
    fs::copy(cache(), tmp / "c", fs::copy_options::recursive);
    std::string m = manifest;
    const auto at = m.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    const auto from = at + key.size() + 4, to = m.find_first_of(",\n", from);
    m.replace(from, to - from, value);
    simreel::test::write_file(tmp / "c" / "manifest.json", m);
  };
  const std::string render_args = "render " + scene_ + " --frames 2:6 --size 64x36 -q --cache " + c + " -o " +
                                  (tmp / "out").string();
  const std::string resume_args = "bake " + scene_ + " --frames 6 -q --resume --cache " + c;
  for (const auto& [key, value, expected] :
       {std::tuple<std::string, std::string, std::string>{"frames", "1000000000000", "/frames: expected an integer in [1, 1000000], found 1000000000000"},
        {"frames", "0", "/frames: expected an integer in [1, 1000000], found 0"},
        {"seed", "-1", "/seed: expected an integer in [0, 9223372036854775807], found -1"},
        {"fps", "\"30\"", "/fps: expected a number in (0, 1000], found \"30\" (string)"},
        {"overrides", "[1]", "/overrides/0: expected a \"POINTER=VALUE\" string, found 1"}}) {
    for (const std::string& args : {render_args, resume_args}) {
      with(key, value);
      const auto r = run_simreel(args, "timeout 60");
      EXPECT_EQ(r.code, 2) << key << "=" << value << ": " << args << "\n" << r.err;
      EXPECT_NE(r.err.find("manifest.json: " + expected), std::string::npos) << r.err;
    }
  }
  for (const fs::path& part : {fs::path("manifest.json"), fs::path("state") / "frame_00003.state"}) {
    for (const std::string& args : {render_args, resume_args}) {
      fs::remove_all(tmp / "c");
      fs::copy(cache(), tmp / "c", fs::copy_options::recursive);
      fs::remove(tmp / "c" / part);
      ASSERT_EQ(::mkfifo((tmp / "c" / part).c_str(), 0600), 0);
      const auto r = run_simreel(args, "timeout 60");
      EXPECT_NE(r.code, 124) << "waited on the FIFO " << part << ": " << args;
      EXPECT_NE(r.code, 0) << part << ": " << args;
      EXPECT_NE(r.err.find(part.filename().string() + ": "), std::string::npos) << r.err;
      EXPECT_NE(r.err.find("FIFO"), std::string::npos) << r.err;
    }
  }
}

TEST_F(CacheRefused, ResumeOfAnotherBakeIsRefused) {
  TempDir tmp;
  fs::copy(cache(), tmp / "c", fs::copy_options::recursive);
  const auto r = run_simreel("bake " + scene_ + " --frames 6 -q --resume --seed 5 --cache " + (tmp / "c").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cannot resume: seed"), std::string::npos) << r.err;
}

// Particle PLY: one 36-byte vertex record per live particle, holding the particles' positions and
// ids in the world's order.
TEST(BakePly, OneRecordPerLiveParticle) {
  TempDir tmp;
  const auto r = run_simreel("bake " + scene_path("fountain").string() + " --frames 21 --ply -q --cache " +
                             (tmp / "c").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const Scene scene = load_scene(scene_path("fountain"));
  SceneWorld sw = build_world(scene);
  advance(sw, scene, 20);
  const simreel::sim::ParticleView v = sw.world.particles(sw.systems[0]);
  ASSERT_GT(v.count, 0u);
  const std::string ply = slurp(tmp / "c" / "ply" / "system0.00020.ply");
  EXPECT_NE(ply.find("element vertex " + std::to_string(v.count) + "\n"), std::string::npos);
  const std::size_t body = ply.find("end_header\n") + 11;
  ASSERT_EQ(ply.size() - body, v.count * 36);
  for (std::size_t i : {std::size_t(0), v.count - 1}) {
    float x[3];
    std::uint32_t id = 0;
    std::memcpy(x, ply.data() + body + 36 * i, sizeof x);
    std::memcpy(&id, ply.data() + body + 36 * i + 32, sizeof id);
    EXPECT_EQ(x[0], v.position[3 * i]);
    EXPECT_EQ(x[2], v.position[3 * i + 2]);
    EXPECT_EQ(id, std::uint32_t(v.id[i]));
  }
}

// Cloth PLY: a header a reader understands, every vertex and every triangle.
TEST(BakePly, ParticlesAndClothAsBinaryPly) {
  TempDir tmp;
  const auto r = run_simreel("bake " + scene_path("flag").string() + " --frames 3 --ply -q --cache " +
                             (tmp / "c").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string cloth = slurp(tmp / "c" / "ply" / "cloth0.00002.ply");
  ASSERT_EQ(cloth.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  const Scene scene = load_scene(scene_path("flag"));
  const std::size_t n = scene.cloths[0].def.rows * scene.cloths[0].def.columns;
  EXPECT_NE(cloth.find("element vertex " + std::to_string(n) + "\n"), std::string::npos);
  const std::size_t body = cloth.find("end_header\n") + 11;
  const std::size_t faces = 2 * (scene.cloths[0].def.rows - 1) * (scene.cloths[0].def.columns - 1);
  EXPECT_EQ(cloth.size() - body, n * (12 + 12 + 4 + 4 + 4 + 12) + faces * 13);
}

}  // namespace
