// Every input bounded, every failure clean (issue 15): ranges checked by one parser, bounded
// reads, clean errors from outputs and imports, no temporaries left behind.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/inotify.h>
#include <sys/stat.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <thread>
#include <utility>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.hpp"
#include "golden.hpp"
#include "json_reader.hpp"
#include "run_options.hpp"
#include "scene.hpp"
#include "simreel/sim/ranges.hpp"
#include "simreel/sim/world.hpp"

extern char** environ;

using simreel::app::json;
using simreel::app::SceneError;
using simreel::test::run_simreel;
using simreel::test::TempDir;
using simreel::test::write_file;
namespace app = simreel::app;
namespace sim = simreel::sim;
namespace fs = std::filesystem;

namespace {

/// The loader's message for `doc`, "" if it loads.
std::string loader_error(const std::string& doc) {
  try {
    (void)app::scene_from_json(json::parse(doc), "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string frames_error(const std::string& text) {
  try {
    (void)app::parse_frames(text);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Every ".tmp-" file under `dir`, one per line ("" when none).
std::string temporaries_under(const fs::path& dir) {
  std::string found;
  if (fs::exists(dir))
    for (const auto& e : fs::recursive_directory_iterator(dir))
      if (has(e.path().filename().string(), ".tmp-")) found += e.path().string() + "\n";
  return found;
}

/// Runs `simreel args...` (with `env`, "NAME=VALUE" each, added) and sends it SIGINT the moment a temporary (".tmp-") is created in
/// `dir` or in a folder created under it: inotify wakes the test at the creation, so the signal
/// lands inside the write's window nearly every time. A child that creates none in 20 s is
/// killed and the test fails instead of hanging. Returns the child's wait status.
int interrupt_at_first_temporary(const std::vector<std::string>& args, const fs::path& dir,
                                 const std::vector<std::string>& env = {}) {
  fs::create_directories(dir);
  const int watch = ::inotify_init1(IN_CLOEXEC);
  EXPECT_GE(watch, 0);
  std::map<int, fs::path> folders;
  // A folder and the folders already in it: one can be made before the watch on its parent
  // is in place (bake makes cache/ and then cache/state/ at once), and its event is then lost.
  std::function<void(const fs::path&)> watch_tree = [&](const fs::path& folder) {
    folders[::inotify_add_watch(watch, folder.c_str(), IN_CREATE)] = folder;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(folder, ec))
      if (e.is_directory(ec)) watch_tree(e.path());
  };
  watch_tree(dir);
  // Built before the fork: the child of a threaded process should only exec.
  std::vector<char*> argv{const_cast<char*>(SIMREEL_BIN)};
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::vector<char*> envp;
  for (const auto& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string_view v(*e);
    const bool replaced = std::any_of(env.begin(), env.end(), [&](const std::string& mine) {
      return v.substr(0, v.find('=') + 1) == std::string_view(mine).substr(0, mine.find('=') + 1);
    });
    if (!replaced) envp.push_back(*e);
  }
  envp.push_back(nullptr);
  const int null_fd = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  const pid_t pid = ::fork();
  if (pid == 0) {
    simreel::test::default_signals_for_child();
    ::dup2(null_fd, STDOUT_FILENO);
    ::dup2(null_fd, STDERR_FILENO);
    ::execve(SIMREEL_BIN, argv.data(), envp.data());
    ::_exit(127);
  }
  ::close(null_fd);
  EXPECT_GE(pid, 0);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  bool created = false;
  alignas(inotify_event) char buf[8192];
  while (!created && std::chrono::steady_clock::now() < until) {
    pollfd ready{watch, POLLIN, 0};
    if (::poll(&ready, 1, 100) != 1) continue;
    const ssize_t n = ::read(watch, buf, sizeof buf);
    for (ssize_t at = 0; at < n && !created;) {
      const auto* e = reinterpret_cast<const inotify_event*>(buf + at);
      const std::string name = e->len > 0 ? e->name : "";
      if ((e->mask & IN_ISDIR) != 0) {
        watch_tree(folders[e->wd] / name);
      } else if (has(name, ".tmp-")) {
        created = true;
      }
      at += ssize_t(sizeof(inotify_event) + e->len);
    }
  }
  ::kill(pid, created ? SIGINT : SIGKILL);
  ::close(watch);
  EXPECT_TRUE(created) << "a temporary is created while it runs";
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, 0), pid);
  return status;
}

}  // namespace

// --- ranges: one parser, one cap -------------------------------------------------------------

TEST(Robust, FramesOptionParsedWithoutOverflowAndCappedLikeTheSceneKey) {
  EXPECT_EQ(app::parse_frames("5"), (std::pair<int, int>{0, 5}));
  EXPECT_EQ(app::parse_frames("2:7"), (std::pair<int, int>{2, 7}));
  EXPECT_EQ(app::parse_frames("1000000"), (std::pair<int, int>{0, 1'000'000}));
  for (const char* bad : {"1000001", "1000000000", "99999999999", "0:99999999999", "4294967297", "0:4294967297",
                          "-1", "+5", " 5", "5 ", "0", "3:3", "4:2", "1:2:3", "", ":", "0x10"}) {
    EXPECT_TRUE(has(frames_error(bad), "expected a count N in [1, 1000000]")) << "--frames " << bad;
  }
  // The scene key has the same cap.
  EXPECT_TRUE(has(loader_error(R"({"frames": 1000001})"), "/frames")) << loader_error(R"({"frames": 1000001})");
  EXPECT_EQ(loader_error(R"({"frames": 1000000})"), "");
}

TEST(Robust, FramesOptionBeyondTheCapExits2BeforeRunning) {
  TempDir d;
  const auto r = run_simreel("simulate demos/scenes/fountain.json --frames 99999999999 --export " +
                             (d / "o.csv").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "--frames 99999999999")) << r.err;
  EXPECT_TRUE(fs::is_empty(d.path)) << "nothing written, no temporary";
}

TEST(Robust, GoldenFramesAndSizeParsedWithoutOverflow) {
  TempDir d;
  const std::string base = R"({"simreel_hashes": 1, "scene": "demos/scenes/fountain.json", )";
  for (const auto& [key, value] : {std::pair{"frames", "0:99999999999"}, std::pair{"frames", "0:4294967297"},
                                   std::pair{"frames", "0:1000001"}, std::pair{"size", "4294967392x72"}}) {
    write_file(d / "g.json", base + "\"size\": \"96x72\", \"frames\": \"0:9\", \"" + key + "\": \"" + value + "\"}");
    // A duplicate key: nlohmann keeps the last, which is the bad value.
    std::string err;
    try {
      (void)app::read_hash_record(d / "g.json");
    } catch (const SceneError& e) {
      err = e.what();
    }
    EXPECT_TRUE(has(err, std::string("/") + key + ": expected")) << key << "=" << value << ": " << err;
  }
}

TEST(Robust, GoldenKeyOfTheWrongTypeGetsOneErrorAndAHashEntryNeedsItsFrame) {
  // A number where the golden wants a string was reported twice ("expected a string, found 64"
  // and then "found \"\""), and "simreel_hashes": 3 as out of range and then as "missing". An
  // entry of "hashes" with no "frame" was taken as frame -1, which no render produces.
  TempDir d;
  const auto errors_of = [&](const std::string& text) {
    write_file(d / "g.json", text);
    try {
      (void)app::read_hash_record(d / "g.json");
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const auto count = [](const std::string& s, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
    return n;
  };
  const std::string hex = R"("phash": "bbcc132bcc934c33", "dhash": "f0f0f0f0f0f0f0f0", "chash": "0000aaaa0000aaaa")";
  std::string err = errors_of(R"({"simreel_hashes": 3, "scene": 5, "size": 64, "frames": 4, "hashes": [{"frame": 0, "phash": 1, "dhash": "f0f0f0f0f0f0f0f0"}]})");
  for (const char* key : {"/simreel_hashes:", "/scene:", "/size:", "/frames:", "/hashes/0/phash:", "/hashes/0/chash:"})
    EXPECT_EQ(count(err, key), 1u) << key << " in:\n" << err;
  EXPECT_TRUE(has(err, "/size: expected a string, found 64")) << err;
  EXPECT_TRUE(has(err, "/hashes/0/chash: missing")) << err;
  err = errors_of(R"({"simreel_hashes": 2, "scene": "s.json", "size": "64x36", "frames": "0:4", "hashes": [{)" + hex + "}]}");
  EXPECT_TRUE(has(err, "/hashes/0/frame: missing")) << err;
  EXPECT_EQ(errors_of(R"({"simreel_hashes": 2, "scene": "s.json", "size": "64x36", "frames": "0:4", "hashes": [{"frame": 3, )" +
                      hex + "}]}"),
            "");
}

TEST(Robust, VectorsFitInFloatsAndPlacedThingsInsideTheWorld) {
  // Each was accepted before: a camera at 1e300 m drew an empty frame (infinite as a float), one
  // at 1e30 m saw nothing, a zero "up" was taken silently, a light of 1e300 or -1 drew garbage,
  // and an emitter at 1e20 m ran and then failed at its first step as "diverged" (exit 1).
  const std::vector<std::pair<std::string, std::string>> bad = {
      {R"({"camera": {"position": [1e300, 0, 1]}})", "/camera/position/0: expected an array of 3 numbers each in [-3e+38, 3e+38]"},
      {R"({"camera": {"position": [1e30, 0, 1]}})", "/camera/position: expected each coordinate within +-1000000 m (simulation.max_distance)"},
      {R"({"camera": {"target": [0, -2e6, 1]}})", "/camera/target: expected each coordinate within +-1000000 m"},
      {R"({"camera": {"path": [{"time": 0, "position": [5e6, 0, 1]}]}})", "/camera/path/0/position: expected each coordinate"},
      {R"({"camera": {"orbit": {"radius": 1e300}}})", "/camera/orbit/radius: expected a number in (0, 1000000]"},
      {R"({"camera": {"up": [0, 0, 0]}})", "/camera/up: expected a non-zero up direction"},
      {R"({"light": {"color": [1e300, 1, 1]}})", "/light/color/0: expected an array of 3 numbers each in [0, 1000]"},
      {R"({"light": {"ambient": [0.3, -1, 0.3]}})", "/light/ambient/1: expected an array of 3 numbers each in [0, 1000]"},
      {R"({"emitters": [{"position": [0, 1e20, 0]}]})", "/emitters/0/position: expected each coordinate within +-1000000 m"},
      // Just past the bound reads as past it (six digits printed "+-1e+06 m ... found [1e+06").
      {R"({"emitters": [{"position": [1000000.5, 0, 0]}]})", "within +-1000000 m (simulation.max_distance), found [1000000.5, 0, 0]"},
      {R"({"camera": {"target": [0, 0, -1000000.25]}})", "within +-1000000 m (simulation.max_distance), found [0, 0, -1000000.25]"},
      {R"({"colliders": [{"type": "sphere", "radius": 1, "position": [0, 0, -1e39]}]})", "/colliders/0/position/2: expected"},
      {R"({"simulation": {"gravity": [0, 0, 1e300]}})", "/simulation/gravity/2: expected"},
  };
  for (const auto& [doc, expected] : bad) EXPECT_TRUE(has(loader_error(doc), expected)) << doc << "\n" << loader_error(doc);
  // Inside: a larger world admits a farther camera and emitter; light above 1 over-exposes but
  // is allowed; looking straight down along "up" is drawn with a chosen perpendicular.
  EXPECT_EQ(loader_error(R"({"simulation": {"max_distance": 1e9}, "camera": {"position": [1e8, 0, 1]},
                             "emitters": [{"position": [0, 1e8, 0]}]})"),
            "");
  EXPECT_EQ(loader_error(R"({"light": {"color": [3, 3, 3]}, "camera": {"position": [0, 0, 10], "target": [0, 0, 0]}})"), "");
}

TEST(Robust, ParticlesAreBornInsideTheWorldsBoundsAndFitInFloats) {
  // Each ran before and stopped at its first step as "diverged" (exit 1) with a message about a
  // particle, not the key: a mass or radius beyond a float's range is born infinite, a particle
  // faster than simulation.max_speed or larger than simulation.max_distance is out of bounds.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {R"({"emitters": [{"mass": 1e300}]})", "/emitters/0/mass: expected a number in [0, 3"},
      {R"({"emitters": [{"mass": {"mean": 1e39, "deviation": 1}}]})", "/emitters/0/mass/mean: expected a number in [0, 3"},
      {R"({"emitters": [{"particle_radius": 1e300}]})", "/emitters/0/particle_radius: expected a number in [0, 3"},
      {R"({"emitters": [{"particle_radius": 1e30}]})",
       "/emitters/0/particle_radius: expected a mean of at most 1000000 m (simulation.max_distance), found 1e+30"},
      {R"({"emitters": [{"start_speed": 1e300}]})",
       "/emitters/0/start_speed: expected a mean of at most 10000 m/s (simulation.max_speed), found 1e+300"},
      {R"({"emitters": [{"start_speed": {"min": 1, "max": 2e4}}]})",
       "/emitters/0/start_speed: expected a max of at most 10000 m/s (simulation.max_speed), found 20000"},
      {R"({"emitters": [{"start_speed": {"mean": 3, "deviation": 1e300}}]})",
       "/emitters/0/start_speed: expected a mean + 5 deviations (or max) of at most 10000 m/s (simulation.max_speed), found 1e+300"},
      {R"({"emitters": [{"particle_radius": {"mean": 0.01, "deviation": 1e300}}]})",
       "/emitters/0/particle_radius: expected a mean + 5 deviations (or max) of at most 1000000 m"},
      {R"({"emitters": [{"shape": "disk", "disk_radius": 1e300}]})",
       "/emitters/0/disk_radius: expected a radius of at most 1000000 m (simulation.max_distance), found 1e+300"},
      {R"({"emitters": [{"shape": "quad", "quad_size": [1, 1e7]}]})", "/emitters/0/quad_size/1: expected a size of at most 1000000 m"},
      {R"({"emitters": [{"shape": "box", "box_size": [1, 1, 1e300]}]})", "/emitters/0/box_size/2: expected a size of at most"},
      {R"({"emitters": [{"shape": "cube", "cube_size": 1e300}]})", "/emitters/0/cube_size: expected a size of at most"},
      {R"({"emitters": [{"shape": "sphere", "sphere_radius": 1e300}]})", "/emitters/0/sphere_radius: expected a radius of at most"},
      {R"({"emitters": [{"rate": 0, "initial_particles": [{"position": [0, 0, 1], "mass": 1e300}]}]})",
       "/emitters/0/initial_particles/0/mass: expected a number in [1e-12, 3"},
      {R"({"emitters": [{"rate": 0, "initial_particles": [{"position": [0, 0, 1], "mass": 1e-300}]}]})",
       "/emitters/0/initial_particles/0/mass: expected a number in [1e-12, 3"},
      {R"({"emitters": [{"rate": 0, "initial_particles": [{"position": [0, 0, 1], "radius": 1e-9}]}]})",
       "/emitters/0/initial_particles/0/radius: expected a number in [1e-06, 3"},
      {R"({"emitters": [{"rate": 0, "initial_particles": [{"position": [0, 0, 1], "radius": 1e30}]}]})",
       "/emitters/0/initial_particles/0/radius: expected a radius of at most 1000000 m"},
      {R"({"emitters": [{"rate": 0, "initial_particles": [{"position": [0, 0, 2e6]}]}]})",
       "/emitters/0/initial_particles/0/position: expected each coordinate of at most 1000000 m (simulation.max_distance), found 2000000"},
      {R"({"emitters": [{"rate": 0, "initial_particles": [{"position": [0, 0, 1], "velocity": [-2e4, 0, 0]}]}]})",
       "/emitters/0/initial_particles/0/velocity: expected each component of at most 10000 m/s (simulation.max_speed), found 20000"},
  };
  for (const auto& [doc, expected] : bad) EXPECT_TRUE(has(loader_error(doc), expected)) << doc << "\n" << loader_error(doc);
  // At the bounds, and beyond the defaults where the world is made larger and faster.
  EXPECT_EQ(loader_error(R"({"emitters": [{"start_speed": 1e4, "particle_radius": 1e6}]})"), "");
  EXPECT_EQ(loader_error(R"({"simulation": {"max_speed": 1e6, "max_distance": 1e9},
                             "emitters": [{"start_speed": 1e5, "particle_radius": 1e7, "mass": 3e38}]})"),
            "");
  // The engine refuses what the loader refuses, for callers of the library.
  for (bool radius : {false, true}) {
    sim::World world;
    sim::ParticleSystemDef def;
    (radius ? def.emitter.radius : def.emitter.mass).mean = 1e300;
    EXPECT_THROW((void)world.add_particle_system(def), std::invalid_argument) << (radius ? "radius" : "mass");
    sim::ParticleSystemDef initial;
    initial.initial_particles.resize(1);
    for (double bad : {1e300, 1e-300}) {
      (radius ? initial.initial_particles[0].radius : initial.initial_particles[0].mass) = bad;
      EXPECT_THROW((void)world.add_particle_system(initial), std::invalid_argument) << (radius ? "radius " : "mass ") << bad;
    }
  }
}

TEST(Robust, IntegerKeysNeverOverflowTheCast) {
  // double(LLONG_MAX) == 2^63: accepted before, then cast to long long (undefined behaviour).
  EXPECT_TRUE(has(loader_error(R"({"seed": 9223372036854775808.0})"), "/seed")) << "2^63";
  EXPECT_TRUE(has(loader_error(R"({"seed": 1e300})"), "/seed"));
  EXPECT_EQ(loader_error(R"({"seed": 9223372036854775807})"), "");
}

TEST(Robust, MaxStepHasALowerBoundSharedByLoaderAndEngine) {
  EXPECT_DOUBLE_EQ(sim::ranges::kWorldMaxStep.min, 1e-6);
  for (const char* v : {"1e-300", "1e-9", "9e-7", "0"})
    EXPECT_TRUE(has(loader_error(std::string(R"({"simulation": {"max_step": )") + v + "}}"),
                    "/simulation/max_step: expected a number in [1e-06, 1]"))
        << v << ": " << loader_error(std::string(R"({"simulation": {"max_step": )") + v + "}}");
  EXPECT_EQ(loader_error(R"({"simulation": {"max_step": 1e-6}})"), "");
  sim::WorldDef def;
  def.max_step = 1e-7;
  EXPECT_THROW(sim::World{def}, std::invalid_argument);
}

TEST(Robust, InternalStepsPerFrameAreCapped) {
  // Loader: 1/fps / max_step beyond the cap names both keys.
  const std::string err = loader_error(R"({"fps": 0.5, "simulation": {"max_step": 1e-6}})");
  EXPECT_TRUE(has(err, "/fps, /simulation/max_step")) << err;
  EXPECT_TRUE(has(err, "at most 1000000")) << err;
  EXPECT_EQ(loader_error(R"({"fps": 1, "simulation": {"max_step": 1e-6}})"), "") << "exactly the cap";
  // Engine: refused before any step, not after hours.
  sim::WorldDef def;
  def.max_step = 1e-6;
  sim::World world(def);
  try {
    (void)world.advance(2.0);
    FAIL() << "advance(2 s) at max_step 1e-6 s ran 2e6 steps";
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(has(e.what(), "max_step")) << e.what();
    EXPECT_TRUE(has(e.what(), "1000000")) << e.what();
  }
  EXPECT_EQ(world.time(), 0.0);
  // --fps on the command line is checked the same way, exit 2 naming the option and the key.
  TempDir d;
  write_file(d / "s.json", R"({"frames": 2, "simulation": {"max_step": 1e-6}})");
  const auto r = run_simreel("simulate " + (d / "s.json").string() + " --fps 0.1 --export " + (d / "o.csv").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "--fps")) << r.err;
  EXPECT_TRUE(has(r.err, "/simulation/max_step")) << r.err;
}

// --- bounded reads -----------------------------------------------------------------------------

TEST(Robust, SceneAndGoldenMustBeRegularFilesOfBoundedSize) {
  TempDir d;
  const fs::path fifo = d / "pipe.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Before: /dev/zero filled memory and a FIFO blocked forever (the test would hang).
  auto r = run_simreel("validate /dev/zero");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "/dev/zero: cannot read scene: not a regular file")) << r.err;
  r = run_simreel("validate " + fifo.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "pipe.json: cannot read scene: not a regular file")) << r.err;
  r = run_simreel("check " + fifo.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "pipe.json: cannot read golden: not a regular file")) << r.err;
  const fs::path big = d / "big.json";
  write_file(big, "{}");
  fs::resize_file(big, app::kMaxJsonBytes + 1);  // sparse
  r = run_simreel("validate " + big.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "expected at most 67108864 (the JSON size limit)")) << r.err;
}

TEST(Robust, MeshColliderThatIsNotARegularFileIsRefusedWithPointer) {
  TempDir d;
  ASSERT_EQ(::mkfifo((d / "m.obj").c_str(), 0600), 0);
  write_file(d / "s.json", R"({"colliders": [{"type": "mesh", "file": "m.obj"}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "/colliders/0/file")) << r.err;
  EXPECT_TRUE(has(r.err, "not a regular file")) << r.err;
}

// assimp 5.2 aborted simreel (an ai_assert) on a PLY file cut short in its vertices, and read one
// cut short in its header forever. It now reads each file in a child process: every mesh reader
// of a scene refuses such a file with exit 2, the pointer and the reason.
TEST(Robust, MeshFileThatCrashesOrHangsAssimpExits2WithThePointer) {
  TempDir d;
  std::ifstream in(fs::path(SIMREEL_SOURCE_DIR) / "tests/assets/data/cube.ply", std::ios::binary);
  const std::string cube((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  write_file(d / "vertices_cut.ply", cube.substr(0, 200));
  write_file(d / "header_cut.ply", cube.substr(0, 120));
  const std::pair<const char*, const char*> readers[] = {
      {R"({"colliders": [{"type": "mesh", "file": "vertices_cut.ply"}]})", "/colliders/0/file"},
      {R"({"bodies": [{"type": "static", "shape": "mesh", "mesh": "vertices_cut.ply"}]})", "/bodies/0/mesh"},
      {R"({"bodies": [{"shape": "mesh", "mesh": "vertices_cut.ply"}]})", "/bodies/0/mesh"},
      {R"({"bodies": [{"shape": "convex_hull", "mesh": "vertices_cut.ply"}]})", "/bodies/0/mesh"},
      {R"({"cloths": [{"mesh": "vertices_cut.ply"}]})", "/cloths/0/mesh"}};
  for (const auto& [doc, pointer] : readers) {
    write_file(d / "s.json", doc);
    const auto r = run_simreel("validate " + (d / "s.json").string(), "timeout 60");
    EXPECT_EQ(r.code, 2) << doc << "\n" << r.err;
    EXPECT_TRUE(has(r.err, pointer)) << r.err;
    EXPECT_TRUE(has(r.err, "vertices_cut.ply: cannot import mesh: assimp crashed reading it (signal SIGABRT)")) << r.err;
  }
  write_file(d / "s.json", R"({"cloths": [{"mesh": "header_cut.ply"}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string(), "SIMREEL_MESH_IMPORT_SECONDS=1 timeout 60");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "/cloths/0/mesh")) << r.err;
  EXPECT_TRUE(has(r.err, "header_cut.ply: cannot import mesh: assimp did not finish reading it within 1 s")) << r.err;
}

TEST(Robust, TextureAMeshFileNamesThatIsMissingCutOrAFifoExits2BeforeAnyOutput) {
  // The renderer read such a texture after the outputs were opened and stopped with exit 1,
  // naming neither the scene nor the mesh file; a FIFO under the name would block the read.
  TempDir d;
  write_file(d / "sq.obj", "mtllib sq.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
                           "usemtl wood\nf 1/1 2/2 3/3\n");
  write_file(d / "sq.mtl", "newmtl wood\nKd 0.5 0.4 0.3\nmap_Kd grain.png\n");
  write_file(d / "s.json", R"({"colliders": [{"type": "mesh", "file": "sq.obj"}], "emitters": [{"rate": 10}]})");
  const auto render = [&] {
    return run_simreel("render " + (d / "s.json").string() + " -o " + (d / "out").string() +
                           " -o " + (d / "out.gif").string() + " --frames 2 --size 32x24",
                       "timeout 60");
  };
  const auto expect_refused = [&](const std::string& why) {
    const auto r = render();
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(has(r.err, "/colliders/0/file: sq.obj's material \"wood\" names the texture grain.png: "
                           "expected an image file (PNG, JPEG, ...) (")) << r.err;
    EXPECT_TRUE(has(r.err, why)) << r.err;
    EXPECT_FALSE(fs::exists(d / "out")) << "a frame folder was made";
    EXPECT_FALSE(fs::exists(d / "out.gif")) << "a video was written";
  };
  expect_refused("grain.png is not a file");
  write_file(d / "grain.png", "\x89PNG\r\n");
  expect_refused("cannot read image " + (d / "grain.png").string());
  fs::remove(d / "grain.png");
  ASSERT_EQ(::mkfifo((d / "grain.png").c_str(), 0600), 0);
  expect_refused("grain.png is not a file");
}

// --- messages ----------------------------------------------------------------------------------

TEST(Robust, NumberOverflowNamesFileLineAndColumnOrTheSetPointer) {
  TempDir d;
  write_file(d / "s.json", "{\n  \"description\": \"1e999 in a string is fine\",\n  \"fps\": 1e400\n}\n");
  auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "s.json:3:10: number 1e400 is out of range")) << r.err;
  EXPECT_FALSE(has(r.err, "json.exception")) << r.err;
  write_file(d / "ok.json", "{}");
  r = run_simreel("validate " + (d / "ok.json").string() + " --set /fps=1e400");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "--set /fps=1e400: /fps: number 1e400 is out of range")) << r.err;
  EXPECT_FALSE(has(r.err, "json.exception")) << r.err;
}

TEST(Robust, DegenerateMeshNamesTheFileAndPointer) {
  TempDir d;
  write_file(d / "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  write_file(d / "s.json", R"({"colliders": [{"type": "plane"}, {"type": "mesh", "file": "flat.obj"}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "/colliders/1/file")) << r.err;
  EXPECT_TRUE(has(r.err, "flat.obj")) << r.err;
}

// A mesh scaled past +-3e38 m was accepted: the engine's doubles held it, the renderer's floats
// made it infinite, and it vanished from the frames while particles still hit it. Each mesh
// reader (collider, static body mesh, dynamic body hull, cloth) refuses it at its "scale"; the
// largest scale that keeps the 1 m tetrahedron finite is accepted. A NaN vertex in the file is
// refused at the file's pointer.
TEST(Robust, MeshScaledBeyondFloatRangeIsRefusedAtItsScale) {
  TempDir d;
  write_file(d / "tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  write_file(d / "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 nan\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  struct Case {
    std::string json, expect;
  };
  const Case cases[] = {
      {R"({"colliders": [{"type": "mesh", "file": "tet.obj", "scale": 1e300}]})", "/colliders/0/scale: expected a scale"},
      {R"({"colliders": [{"type": "mesh", "file": "tet.obj", "scale": [1, 1e39, 1]}]})", "/colliders/0/scale: expected a scale"},
      {R"({"bodies": [{"type": "static", "shape": "mesh", "mesh": "tet.obj", "scale": 1e300}]})", "/bodies/0/scale: expected a scale"},
      {R"({"bodies": [{"shape": "convex_hull", "mesh": "tet.obj", "scale": 1e300}]})", "/bodies/0/scale: expected a scale"},
      {R"({"cloths": [{"mesh": "tet.obj", "scale": 1e300}]})", "/cloths/0/scale: expected a scale"},
      {R"({"colliders": [{"type": "mesh", "file": "nan.obj"}]})", "/colliders/0/file: "},
  };
  for (const Case& c : cases) {
    write_file(d / "s.json", c.json);
    const auto r = run_simreel("validate " + (d / "s.json").string());
    EXPECT_EQ(r.code, 2) << c.json << "\n" << r.err;
    EXPECT_TRUE(has(r.err, c.expect)) << c.json << "\n" << r.err;
  }
  write_file(d / "s.json", R"({"colliders": [{"type": "mesh", "file": "tet.obj", "scale": 2.9e38}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 0) << r.err;
}

// Bad input, refused before the run (exit 2; they failed with exit 1 once it was under way).
// Cli.BadOutputOptionsExit2 takes every command that writes an output.
TEST(Robust, OutputsUnderAFileNameTheOutputAndTheFile) {
  TempDir d;
  write_file(d / "f", "x");
  auto r = run_simreel("simulate demos/scenes/fountain.json --frames 2 --export " + (d / "f" / "o.csv").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "--export " + (d / "f" / "o.csv").string() + ": " + (d / "f").string() +
                             " is a regular file, expected a folder"))
      << r.err;
  r = run_simreel("render demos/scenes/fountain.json --frames 2 --size 32x32 -q -o " + (d / "f" / "v.mp4").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "-o " + (d / "f" / "v.mp4").string() + ": " + (d / "f").string() +
                             " is a regular file, expected a folder"))
      << r.err;
  EXPECT_EQ(std::distance(fs::directory_iterator(d.path), fs::directory_iterator()), 1) << "nothing but f";
}

TEST(Robust, AnOutputThatIsADeviceFifoOrFolderOrNamedTwiceExits2BeforeRunning) {
  // The atomic rename would replace a FIFO or device (as root, `--hash /dev/full` turned
  // /dev/full into a JSON file), and two outputs of one name raced to rename over it.
  TempDir d;
  const std::string fifo = (d / "pipe").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_directory(d / "folder");
  const std::string scene = "demos/scenes/smoke.json", quick = " --frames 2 --size 32x18 -q";
  const std::string png = (d / "png").string(), folder = (d / "folder").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"render " + scene + quick + " -o " + png + " --hash " + fifo, "--hash " + fifo + ": is a FIFO"},
      {"render " + scene + quick + " -o " + png + " --hash " + folder, "is a directory, expected a regular file"},
      {"render " + scene + quick + " -o " + fifo, "-o " + fifo + ": is a FIFO, expected a folder"},
      {"render " + scene + quick + " -o " + png + ".gif -o " + png + "/../png.gif", "the same path as -o"},
      {"simulate " + scene + " --frames 2 --export " + fifo, "--export " + fifo + ": is a FIFO"},
      {"simulate " + scene + " --frames 2 --export " + png + ".csv --export-joints " + png + ".csv", "the same path"},
      {"check tests/golden/smoke.json --junit " + folder + ".xml --report " + fifo, "--report " + fifo + ": is a FIFO"},
  };
  for (const auto& [args, expected] : cases) {
    const auto r = run_simreel(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_TRUE(has(r.err, expected)) << args << "\n" << r.err;
  }
  EXPECT_EQ(fs::status(fifo).type(), fs::file_type::fifo);
  EXPECT_TRUE(fs::is_directory(folder));
  EXPECT_FALSE(fs::exists(png + ".gif"));
  EXPECT_FALSE(fs::exists(png + ".csv"));
}

TEST(Robust, BitrateOutsideItsRangeOrMalformedExits2BeforeRunning) {
  // "--bitrate 0k" rendered (ffmpeg took a zero target as none) and "1.2.3M" passed the option's
  // character check, then failed in the video writer with exit 1 after the simulation began.
  TempDir d;
  for (const std::string rate : {"0k", "1.2.3M", "99999M", "500"}) {
    const auto r = run_simreel("render demos/scenes/smoke.json --frames 2 --size 32x18 -q -o " + (d / "v.mp4").string() +
                               " --bitrate " + rate);
    EXPECT_EQ(r.code, 2) << rate << "\n" << r.err;
    EXPECT_TRUE(has(r.err, "--bitrate " + rate + ": expected a number with an optional k or M suffix in [1k, 10000M]"))
        << r.err;
    EXPECT_FALSE(fs::exists(d / "v.mp4"));
  }
}

TEST(Robust, FfmpegThatFailsButExitsZeroMakesRenderExit1WithNoVideo) {
  TempDir d;
  fs::create_directories(d / "bin");
  write_file(d / "bin" / "ffmpeg",
             "#!/bin/sh\ncat > /dev/null\nfor last; do :; done\nprintf 'partial' > \"$last\"\n"
             "echo 'Error writing trailer: No space left on device' >&2\nexit 0\n");
  fs::permissions(d / "bin" / "ffmpeg", fs::perms::owner_all);
  const auto r = run_simreel("render demos/scenes/fountain.json --frames 3 --size 32x32 -q -o " + (d / "v.mp4").string(),
                             "PATH=" + (d / "bin").string() + ":/usr/bin:/bin");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(has(r.err, "No space left on device")) << r.err;
  EXPECT_FALSE(fs::exists(d / "v.mp4"));
  for (const auto& e : fs::directory_iterator(d.path))
    EXPECT_FALSE(has(e.path().filename().string(), ".tmp-")) << e.path();
}

// --- goldens cannot read any file --------------------------------------------------------------

TEST(Robust, GoldenScenePathsStayInsideTheGoldensFolder) {
  TempDir d;
  fs::create_directories(d / "g");
  write_file(d / "secret.json", R"({"fps": "TOKEN-1234"})");
  const std::string head = R"({"simreel_hashes": 1, "size": "32x32", "frames": "0:2", "hashes": [], "scene": )";
  // Climbing out, absolute, and a symbolic link out are refused before anything is read.
  for (const std::string& scene : {std::string("../secret.json"), (d / "secret.json").string(), std::string("link.json")}) {
    write_file(d / "g" / "golden.json", head + "\"" + scene + "\"}");
    fs::remove(d / "g" / "link.json");
    fs::create_symlink(d / "secret.json", d / "g" / "link.json");
    const auto r = run_simreel("check " + (d / "g" / "golden.json").string());
    EXPECT_EQ(r.code, 2) << scene << ": " << r.err;
    EXPECT_TRUE(has(r.err, "outside the golden's folder")) << r.err;
    EXPECT_TRUE(has(r.err, "--allow-outside")) << r.err;
    EXPECT_FALSE(has(r.err, "TOKEN-1234")) << r.err;
  }
  // With --allow-outside the file is read, but a non-scene's contents are still not echoed.
  write_file(d / "g" / "golden.json", head + "\"../secret.json\"}");
  auto r = run_simreel("check --allow-outside " + (d / "g" / "golden.json").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "is not a valid scene")) << r.err;
  EXPECT_FALSE(has(r.err, "TOKEN-1234")) << r.err;
  // /dev/zero as the scene: refused as not a regular file, not read until memory runs out.
  write_file(d / "g" / "golden.json", head + "\"/dev/zero\"}");
  r = run_simreel("check --allow-outside " + (d / "g" / "golden.json").string());
  EXPECT_EQ(r.code, 2) << r.err;
  // A scene beside the golden is found relative to the golden, whatever the working directory.
  write_file(d / "g" / "s.json", R"({"frames": 2})");
  write_file(d / "g" / "golden.json", head + "\"s.json\"}");
  r = run_simreel("check " + (d / "g" / "golden.json").string());
  EXPECT_TRUE(has(r.err, "holds no hashes")) << "the scene loaded, then the empty golden was refused: " << r.err;
  // A valid scene that only the golden's /set overrides break: the command the message gives
  // carries them (quoted for the shell), so it shows the error; without them `validate` said ok.
  write_file(d / "g" / "golden.json", head + R"("s.json", "set": ["/nope=1", "/description=it's"]})");
  r = run_simreel("check " + (d / "g" / "golden.json").string());
  EXPECT_EQ(r.code, 2) << r.err;
  const std::size_t at = r.err.find("run `simreel validate ");
  ASSERT_NE(at, std::string::npos) << r.err;
  const std::size_t from = at + std::string("run `simreel ").size();
  const std::string command = r.err.substr(from, r.err.find('`', from) - from);
  EXPECT_TRUE(has(command, "--set /nope=1 --set '/description=it'\\''s'")) << command;
  const auto shown = run_simreel(command);  // (from the same working directory as the check)
  EXPECT_EQ(shown.code, 2) << shown.err;
  EXPECT_TRUE(has(shown.err, "/nope: unknown key")) << shown.err;
}

// --- no temporaries left behind ----------------------------------------------------------------

TEST(Robust, SecondInterruptEndsFfmpegAndRemovesTheTemporaries) {
  TempDir d;
  fs::create_directories(d / "bin");
  // A stand-in ffmpeg that stores the frames and then takes long to "write its trailer".
  write_file(d / "bin" / "ffmpeg", "#!/bin/sh\necho $$ > " + (d / "ffmpeg.pid").string() +
                                       "\nfor last; do :; done\ncat > \"$last\"\nsleep 60\n");
  fs::permissions(d / "bin" / "ffmpeg", fs::perms::owner_all);
  write_file(d / "s.json", R"({"frames": 1000, "emitters": [{"name": "a", "rate": 50}]})");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    simreel::test::default_signals_for_child();
    const std::string path = (d / "bin").string() + ":/usr/bin:/bin";
    ::setenv("PATH", path.c_str(), 1);
    (void)!std::freopen("/dev/null", "w", stdout);
    (void)!std::freopen((d / "err.txt").c_str(), "w", stderr);
    const std::string scene = (d / "s.json").string(), mp4 = (d / "out" / "v.mp4").string();
    ::execl(SIMREEL_BIN, SIMREEL_BIN, "render", scene.c_str(), "-q", "--size", "32x32", "-o", mp4.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  auto temporaries = [&] {
    int n = 0;
    if (fs::exists(d / "out"))
      for (const auto& e : fs::directory_iterator(d / "out")) n += has(e.path().filename().string(), ".tmp-") ? 1 : 0;
    return n;
  };
  for (int i = 0; i < 400 && !(fs::exists(d / "ffmpeg.pid") && temporaries() > 0); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  ASSERT_GT(temporaries(), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(pid, SIGINT);  // first: finish the frame, close ffmpeg's input, wait for it
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ::kill(pid, SIGINT);  // second: hard stop while ffmpeg "writes its trailer"
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status << " " << simreel::test::slurp(d / "err.txt");
  EXPECT_EQ(temporaries(), 0) << "the video's temporary was removed";
  EXPECT_FALSE(fs::exists(d / "out" / "v.mp4"));
  const pid_t ffmpeg = std::stoi(simreel::test::slurp(d / "ffmpeg.pid"));
  bool gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {
    gone = ::kill(ffmpeg, 0) != 0 || fs::exists("/proc/" + std::to_string(ffmpeg) + "/stat") == false ||
           has(simreel::test::slurp("/proc/" + std::to_string(ffmpeg) + "/stat"), ") Z");
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(gone) << "ffmpeg " << ffmpeg << " still runs";
  if (!gone) ::kill(ffmpeg, SIGKILL);
}

// --- memory estimated up front -----------------------------------------------------------------

TEST(Robust, MemoryIsEstimatedUpFrontAgainstABudget) {
  TempDir d;
  write_file(d / "s.json", R"({"frames": 2, "emitters": [{"name": "a", "rate": 1e9, "max_particles": 50000000}]})");
  const std::string csv = " --export " + (d / "o.csv").string();
  // 5e7 particles: about 9 GiB estimated, refused under a 1 GiB budget before anything runs.
  auto r = run_simreel("simulate " + (d / "s.json").string() + " --memory-limit 1G" + csv);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "/emitters/0/max_particles")) << r.err;
  EXPECT_TRUE(has(r.err, "expected at most 1024 MiB")) << r.err;
  r = run_simreel("simulate " + (d / "s.json").string() + csv, "SIMREEL_MEMORY_LIMIT=512M");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "expected at most 512 MiB")) << r.err;
  r = run_simreel("simulate " + (d / "s.json").string() + " --memory-limit lots" + csv);
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "--memory-limit lots: expected a number of bytes")) << r.err;
  // Framebuffers count when rendering: 8192x8192 with 16 samples.
  write_file(d / "r.json", R"({"frames": 1, "render": {"msaa": 16}})");
  r = run_simreel("render " + (d / "r.json").string() + " --size 8192x8192 --memory-limit 2G -q -o " +
                  (d / "png").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "/render/width, height, msaa")) << r.err;
  EXPECT_FALSE(fs::exists(d / "png"));
  // The estimate itself.
  const app::Scene small = app::scene_from_json(json::parse(R"({"emitters": [{"name": "a", "max_particles": 1000}]})"), "s");
  const auto m = app::estimate_memory(small, false);
  ASSERT_EQ(m.items.size(), 1u);
  EXPECT_GT(m.bytes, 1000u * 64u);
  EXPECT_LT(m.bytes, 1000u * 1024u);
}

TEST(Robust, SimulateStoppedByAnErrorOrASignalLeavesNoTemporary) {
  TempDir d;
  // Diverges (explicit Euler on a stiff spring): exit 1, no CSV, no temporary.
  write_file(d / "nan.json", R"({"frames": 30, "emitters": [{"name": "a", "rate": 100, "integrator": "explicit_euler"}],
    "attractor_springs": [{"system": "a", "stiffness": 1e12, "anchor": [0, 0, 1]}]})");
  const auto r = run_simreel("simulate " + (d / "nan.json").string() + " --export " + (d / "out" / "o.csv").string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(!fs::exists(d / "out") || fs::is_empty(d / "out"));
  // Interrupted: the signal ends it and the temporary goes with it, also when the signal comes
  // the moment the temporary is created (five times): handlers installed only after the file
  // was opened left it behind.
  write_file(d / "long.json", R"({"frames": 1000000, "emitters": [{"name": "a", "rate": 2000}]})");
  for (int attempt = 0; attempt < 5; ++attempt) {
    const fs::path dir = d / ("sig" + std::to_string(attempt));
    const int status = interrupt_at_first_temporary(
        {"simulate", (d / "long.json").string(), "--export", (dir / "o.csv").string()}, dir);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
    EXPECT_EQ(temporaries_under(dir), "") << attempt;
  }
}

/// The pids of running processes whose command line mentions `text`.
std::vector<pid_t> processes_mentioning(const std::string& text) {
  std::vector<pid_t> found;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline;
    try {
      cmdline = simreel::test::slurp(e.path() / "cmdline");
    } catch (...) {
      continue;
    }
    const std::string stat = fs::exists(e.path() / "stat") ? simreel::test::slurp(e.path() / "stat") : "";
    if (has(cmdline, text) && !has(stat, ") Z")) found.push_back(pid_t(std::stol(name)));
  }
  return found;
}

// Every command, not only those with their own handlers (render, simulate): bake writes a state
// file per frame through write_file_atomic (temporary, fsync, rename), and a Ctrl-C inside that
// window ended the program by the default action and left the temporary in the cache.
TEST(Robust, BakeInterruptedWhileWritingAFrameLeavesNoTemporary) {
  TempDir d;
  write_file(d / "long.json", R"({"frames": 1000000, "emitters": [{"name": "a", "rate": 500}]})");
  for (int attempt = 0; attempt < 5; ++attempt) {
    const fs::path dir = d / ("sig" + std::to_string(attempt));
    const int status =
        interrupt_at_first_temporary({"bake", (d / "long.json").string(), "-q", "--cache", (dir / "cache").string()}, dir);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
    EXPECT_EQ(temporaries_under(dir), "") << attempt;
  }
  // What was baked before the signal still resumes.
  const auto r = run_simreel("bake " + (d / "long.json").string() + " -q --frames 3 --resume --cache " +
                             (d / "sig0" / "cache").string());
  EXPECT_EQ(r.code, 0) << r.err;
}

// A sweep's children lead their own process groups, so the sweep passes a signal on: they stop,
// the sweep waits for them, removes its scratch folder and ends by the signal. Before, the sweep
// died alone and left its children rendering and its scratch folder in $TMPDIR.
TEST(Robust, SweepInterruptedStopsItsChildrenAndLeavesNothingBehind) {
  TempDir d;
  fs::create_directories(d / "bin");
  fs::create_directories(d / "tmp");
  // A stand-in ffmpeg, so that the children render every frame of a long range quickly.
  write_file(d / "bin" / "ffmpeg", "#!/bin/sh\nfor last; do :; done\ncat > \"$last\"\n");
  fs::permissions(d / "bin" / "ffmpeg", fs::perms::owner_all);
  const fs::path scene = d / "s.json";
  write_file(scene, R"({"frames": 1000000, "emitters": [{"name": "a", "rate": 50}]})");
  const int status = interrupt_at_first_temporary(
      {"sweep", scene.string(), "--vary", "/emitters/0/rate=10,20,30", "--jobs", "2", "--size", "32x32",
       "--contact-sheet", (d / "sheet.png").string(), "-o", (d / "out").string()},
      d / "out", {"PATH=" + (d / "bin").string() + ":/usr/bin:/bin", "TMPDIR=" + (d / "tmp").string()});
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
  auto left = processes_mentioning(scene.string());
  for (int i = 0; i < 50 && !left.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    left = processes_mentioning(scene.string());
  }
  EXPECT_TRUE(left.empty()) << left.size() << " children still run, e.g. " << left.front();
  for (const pid_t pid : left) ::kill(pid, SIGKILL);
  EXPECT_TRUE(fs::is_empty(d / "tmp")) << fs::directory_iterator(d / "tmp")->path();
  EXPECT_EQ(temporaries_under(d / "out"), "");
  EXPECT_FALSE(fs::exists(d / "sheet.png"));
}
