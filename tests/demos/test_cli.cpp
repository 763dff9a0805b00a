// The program as a user runs it: exit codes, messages, outputs, determinism, the golden frame.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_util.hpp"

using simreel::test::run_simreel;
using simreel::test::slurp;
using simreel::test::TempDir;
using simreel::test::write_file;
namespace fs = std::filesystem;

namespace {

// A small scene: a jet onto a plane, quick to simulate.
const char* kSmallScene = R"({
  "seed": 3, "fps": 30, "frames": 20,
  "colliders": [{"type": "plane", "restitution": 0.5}],
  "emitters": [{"name": "jet", "rate": 200, "start_speed": {"mean": 4, "deviation": 0.5},
                "spread_deg": {"mean": 0, "deviation": 10}, "lifetime": 2, "position": [0, 0, 0.1]}]
})";

int count_lines(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST(Cli, MissingSceneFileExits2NamingTheFile) {
  const auto r = run_simreel("validate /nonexistent/scene.json");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/nonexistent/scene.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no such file"), std::string::npos) << r.err;
}

TEST(Cli, InvalidJsonExits2WithLineAndColumn) {
  TempDir d;
  write_file(d / "bad.json", "{\n  \"fps\": 30,\n  \"frames\": 10,,\n}\n");
  const auto r = run_simreel("render " + (d / "bad.json").string() + " -o " + (d / "out").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "bad.json").string() + ":3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("invalid JSON"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "out")) << "nothing may be written for a bad scene";
}

TEST(Cli, WrongTypeAtPointerExits2) {
  TempDir d;
  write_file(d / "s.json", R"({"emitters": [{"rate": "lots"}]})");
  const auto r = run_simreel("simulate " + (d / "s.json").string() + " --export " + (d / "x.csv").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "s.json").string() + ": /emitters/0/rate: expected a number in [0, 1000000000], found \"lots\""),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(d / "x.csv"));
}

TEST(Cli, UnknownKeyExits2WithHint) {
  TempDir d;
  write_file(d / "s.json", R"({"emitters": [{"start_sped": 3}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/emitters/0/start_sped: unknown key \"start_sped\"; did you mean \"start_speed\"?"),
            std::string::npos)
      << r.err;
}

TEST(Cli, BadSetExits2NamingPointer) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  auto r = run_simreel("validate " + (d / "s.json").string() + " --set /emitters/5/rate=3");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/emitters/5/rate"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find((d / "s.json").string()), std::string::npos) << r.err;
  r = run_simreel("validate " + (d / "s.json").string() + " --set /emitters/0/rate=-4");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/emitters/0/rate: expected a number in [0, 1000000000], found -4"), std::string::npos) << r.err;
  r = run_simreel("validate " + (d / "s.json").string() + " --set nonsense");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("POINTER=VALUE"), std::string::npos) << r.err;
}

TEST(Cli, BadUsageExits2) {
  EXPECT_EQ(run_simreel("").code, 2);
  EXPECT_EQ(run_simreel("frobnicate x.json").code, 2);
  const auto r = run_simreel("render demos/scenes/fountain.json --size 12x7");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--size 12x7"), std::string::npos) << r.err;
}

TEST(Cli, EveryDemoSceneValidates) {
  for (const auto& entry : fs::directory_iterator(fs::path(SIMREEL_SOURCE_DIR) / "demos/scenes")) {
    const auto r = run_simreel("validate " + entry.path().string());
    EXPECT_EQ(r.code, 0) << entry.path() << "\n" << r.err;
    EXPECT_EQ(r.out, "ok\n");
  }
}

TEST(Cli, SimulateExportsCsvWithHeaderAndSetOverrides) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  auto r = run_simreel("simulate " + (d / "s.json").string() + " --export " + (d / "a.csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string csv = slurp(d / "a.csv");
  EXPECT_EQ(csv.rfind("frame,time,system,id,x,y,z,vx,vy,vz\n", 0), 0u);
  EXPECT_NE(csv.find("\n19,"), std::string::npos) << "last frame (19) exported";
  EXPECT_NE(csv.find(",jet,0,"), std::string::npos);
  // Rate 0 through --set: nothing is emitted, the file holds only the header.
  r = run_simreel("simulate " + (d / "s.json").string() + " --set /emitters/0/rate=0 --export " +
                  (d / "b.csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(count_lines(slurp(d / "b.csv")), 1);
}

// Cloth (issue 6): vertices are exported with system = the cloth's name; a bad cloth value stops
// with exit 2 naming the file and the pointer.
const char* kClothScene = R"({
  "fps": 30, "frames": 5,
  "colliders": [{"type": "plane"}],
  "cloths": [{"name": "sheet", "rows": 4, "columns": 5, "size_m": [0.4, 0.3], "mass": 0.05,
              "position": [0, 0, 1], "pins": "two_corners"}]
})";

TEST(Cli, SimulateExportsClothVertices) {
  TempDir d;
  write_file(d / "s.json", kClothScene);
  const auto r = run_simreel("simulate " + (d / "s.json").string() + " --export " + (d / "c.csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string csv = slurp(d / "c.csv");
  EXPECT_EQ(count_lines(csv), 1 + 5 * 20);  // header + 5 frames x 20 vertices
  EXPECT_NE(csv.find("\n4,"), std::string::npos);
  EXPECT_NE(csv.find(",sheet,19,"), std::string::npos);
}

TEST(Cli, BadClothValueExits2NamingPointer) {
  TempDir d;
  write_file(d / "s.json", kClothScene);
  auto r = run_simreel("validate " + (d / "s.json").string() + " --set /cloths/0/max_strain=-1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "s.json").string() + ": /cloths/0/max_strain: expected a number"), std::string::npos)
      << r.err;
  r = run_simreel("validate " + (d / "s.json").string() + " --set /cloths/0/pins=corners");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/cloths/0/pins"), std::string::npos) << r.err;
  write_file(d / "t.json", R"({"cloths": [{"stretch": {"stifness": 3}}]})");
  r = run_simreel("validate " + (d / "t.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("did you mean \"stiffness\""), std::string::npos) << r.err;
}

TEST(Cli, SameSeedSameCsvOtherSeedDiffers) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const std::string base = "simulate " + (d / "s.json").string();
  ASSERT_EQ(run_simreel(base + " --export " + (d / "a.csv").string()).code, 0);
  ASSERT_EQ(run_simreel(base + " --export " + (d / "b.csv").string()).code, 0);
  ASSERT_EQ(run_simreel(base + " --seed 4 --export " + (d / "c.csv").string()).code, 0);
  const std::string a = slurp(d / "a.csv"), b = slurp(d / "b.csv"), c = slurp(d / "c.csv");
  EXPECT_GT(count_lines(a), 100);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(Cli, RenderWritesPngsAndMp4) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const auto r = run_simreel("render " + (d / "s.json").string() + " --frames 6 --size 96x55 -o " +
                             (d / "png").string() + " -o " + (d / "v.mp4").string());
  ASSERT_EQ(r.code, 0) << r.err;
  for (int i = 0; i < 6; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", i);
    EXPECT_TRUE(fs::exists(d / "png" / name)) << name;
  }
  EXPECT_FALSE(fs::exists(d / "png" / "frame_00006.png"));
  ASSERT_TRUE(fs::exists(d / "v.mp4"));
  const std::string mp4 = slurp(d / "v.mp4");
  EXPECT_EQ(mp4.substr(4, 4), "ftyp") << "an MP4 file";
  for (const auto& e : fs::directory_iterator(d.path))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "temporary left: " << e.path();
}

TEST(Cli, WithoutFfmpegPngsAreStillWritten) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const auto r = run_simreel("render " + (d / "s.json").string() + " --frames 3 --size 64x48 -o " +
                                 (d / "png").string() + " -o " + (d / "v.mp4").string(),
                             "PATH=/nonexistent");
  EXPECT_EQ(r.code, 1) << "the video was asked for and not made";
  EXPECT_NE(r.err.find("ffmpeg"), std::string::npos) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_TRUE(fs::exists(d / "png" / "frame_00002.png"));
  EXPECT_FALSE(fs::exists(d / "v.mp4"));
}

TEST(Cli, HashPrintsSixteenHexDigitsPerImage) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  ASSERT_EQ(run_simreel("render " + (d / "s.json").string() + " --frames 1 --size 64x48 -o " + (d / "p").string()).code, 0);
  const auto r = run_simreel("hash " + (d / "p" / "frame_00000.png").string());
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_GE(r.out.size(), 17u);
  EXPECT_EQ(r.out.find_first_not_of("0123456789abcdef"), 16u) << r.out;
  EXPECT_NE(r.out.find("frame_00000.png"), std::string::npos);
  const auto bad = run_simreel("hash " + (d / "missing.png").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("missing.png"), std::string::npos);
}

// One frame of the default demo, compared with a perceptual hash recorded after looking at it
// (tests/golden/README.md says how to re-record).
TEST(Golden, FountainFrameMatchesRecordedHash) {
  const auto golden = nlohmann::json::parse(slurp(fs::path(SIMREEL_SOURCE_DIR) / "tests/golden/fountain.json"));
  const int frame = golden.at("frame").get<int>();
  TempDir d;
  const auto r = run_simreel("render " + golden.at("scene").get<std::string>() + " -q --frames " +
                             std::to_string(frame + 1) + " --size " + golden.at("size").get<std::string>() +
                             " --seed " + std::to_string(golden.at("seed").get<int>()) + " -o " + d.path.string());
  ASSERT_EQ(r.code, 0) << r.err;
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", frame);
  for (const char* algorithm : {"phash", "dhash"}) {
    const auto h = run_simreel(std::string("hash --algorithm ") + algorithm + " " + (d / name).string());
    ASSERT_EQ(h.code, 0) << h.err;
    const std::uint64_t got = std::stoull(h.out.substr(0, 16), nullptr, 16);
    const std::uint64_t want = std::stoull(golden.at(algorithm).get<std::string>(), nullptr, 16);
    const int distance = __builtin_popcountll(got ^ want);
    EXPECT_LE(distance, golden.at("tolerance").get<int>())
        << algorithm << " " << h.out.substr(0, 16) << " vs golden " << golden.at(algorithm)
        << " recorded on " << golden.at("gl_renderer") << " / " << golden.at("gl_version") << "; this run: " << r.out;
  }
  // The golden must be able to fail: the same frame without the fountain is out of tolerance
  // for dHash (pHash's low frequencies barely see a thin spray at this size).
  TempDir e;
  ASSERT_EQ(run_simreel("render " + golden.at("scene").get<std::string>() + " -q --frames " + std::to_string(frame + 1) +
                        " --size " + golden.at("size").get<std::string>() + " --seed " +
                        std::to_string(golden.at("seed").get<int>()) + " --set /emitters/0/rate=0 -o " + e.path.string())
                .code,
            0);
  const auto h = run_simreel("hash --algorithm dhash " + (e / name).string());
  const std::uint64_t got = std::stoull(h.out.substr(0, 16), nullptr, 16);
  const std::uint64_t want = std::stoull(golden.at("dhash").get<std::string>(), nullptr, 16);
  EXPECT_GT(__builtin_popcountll(got ^ want), golden.at("tolerance").get<int>());
}

TEST(Cli, BrokenMeshFileExits2NamingSceneFilePointerAndMesh) {
  TempDir d;
  write_file(d / "rock.obj", "v 0 0 0\n# no faces\n");
  write_file(d / "s.json", R"({"colliders": [{"type": "plane"}, {"type": "mesh", "file": "rock.obj"}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "s.json").string() + ": /colliders/1/file: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find((d / "rock.obj").string() + ": cannot import mesh: "), std::string::npos) << r.err;
}

TEST(Cli, BadColliderResponseValuesExit2) {
  TempDir d;
  write_file(d / "s.json", R"({"colliders": [{"type": "sphere", "radius": 0.2,
      "collider": {"on_hit": "explode", "split": {"size_fraction": 2}}}],
      "emitters": [{"collide_particles": "yes"}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/colliders/0/collider/on_hit: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/colliders/0/collider/split/size_fraction: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/emitters/0/collide_particles: "), std::string::npos) << r.err;
}
