// The program as a user runs it: exit codes, messages, outputs, determinism, the golden frame.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "simreel/render/image.hpp"

using simreel::test::count_lines;
using simreel::test::kGoldenScene;
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

// Quadratic drag (issue 15) as a user sets it: `drag_quadratic` (c2, kg/m) in the scene or by
// --set. A 2 g particle dropped from 500 m falls at v(t) = v_t tanh(g t / v_t) with the terminal
// speed v_t = sqrt(m g / c2): 9.897 m/s at t = 4 s for c2 = 2e-4 kg/m (v_t = 9.905), and half of
// that with --set c2 = 8e-4. Without the key it would fall at 39 m/s. A negative value exits 2
// naming the pointer.
const char* kQuadraticDragScene = R"({
  "fps": 30, "frames": 121,
  "emitters": [{"name": "drop", "rate": 0, "bursts": [{"time": 0, "count": 1}],
                "start_speed": 0, "mass": 0.002, "lifetime": 10, "position": [0, 0, 500],
                "drag_quadratic": 2e-4}]
})";

double last_vz(const std::string& csv) {
  const auto start = csv.rfind('\n', csv.size() - 2) + 1;
  std::stringstream row(csv.substr(start));
  std::string cell;
  std::vector<std::string> cells;
  while (std::getline(row, cell, ',')) cells.push_back(cell);
  return cells.size() == 10 ? std::stod(cells[9]) : 0.0;
}

TEST(Cli, QuadraticDragKeyGivesTheTerminalSpeed) {
  TempDir d;
  write_file(d / "s.json", kQuadraticDragScene);
  const auto speed_at_4s = [](double c2) {
    const double g = 9.81, vt = std::sqrt(0.002 * g / c2);
    return vt * std::tanh(g * 4.0 / vt);
  };
  auto r = run_simreel("simulate " + (d / "s.json").string() + " --export " + (d / "a.csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NEAR(-last_vz(slurp(d / "a.csv")) / speed_at_4s(2e-4), 1.0, 2e-4);
  r = run_simreel("simulate " + (d / "s.json").string() +
                  " --set /emitters/0/drag_quadratic=8e-4 --export " + (d / "b.csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NEAR(-last_vz(slurp(d / "b.csv")) / speed_at_4s(8e-4), 1.0, 2e-4);
  r = run_simreel("validate " + (d / "s.json").string() + " --set /emitters/0/drag_quadratic=-1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "s.json").string() + ": /emitters/0/drag_quadratic: expected a number"),
            std::string::npos)
      << r.err;
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

std::string frame_name(int i) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", i);
  return name;
}

std::string probe(const fs::path& video, const std::string& entries) {
  std::string out;
  const std::string cmd = "ffprobe -v error -count_frames -show_entries " + entries + " -of csv=p=0 '" +
                          video.string() + "' 2>/dev/null";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) out += buf;
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

TEST(Cli, FrameRangeSimulatesFromZeroAndWritesOnlyTheRange) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const std::string base = "render " + (d / "s.json").string() + " -q --size 64x48 -o ";
  ASSERT_EQ(run_simreel(base + (d / "all").string() + " --frames 8").code, 0);
  const auto r = run_simreel(base + (d / "part").string() + " --frames 5:8");
  ASSERT_EQ(r.code, 0) << r.err;
  for (int i = 0; i < 8; ++i) EXPECT_EQ(fs::exists(d / "part" / frame_name(i)), i >= 5) << i;
  // Frame 6 of the range is frame 6 of the whole run, byte for byte: the jet is in the air.
  EXPECT_EQ(slurp(d / "part" / frame_name(6)), slurp(d / "all" / frame_name(6)));
  EXPECT_NE(slurp(d / "all" / frame_name(5)), slurp(d / "all" / frame_name(6)));
  for (const char* bad : {"0", "5:5", "7:3", "a:b", "3:", "-2"}) {
    const auto e = run_simreel(base + (d / "bad").string() + " --frames " + bad);
    EXPECT_EQ(e.code, 2) << bad;
    EXPECT_NE(e.err.find("--frames"), std::string::npos) << e.err;
  }
  EXPECT_FALSE(fs::exists(d / "bad"));
}

TEST(Cli, OutputsDoNotDependOnWriterThreads) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const std::string base = "render " + (d / "s.json").string() + " -q --size 80x60 --frames 6 -o ";
  ASSERT_EQ(run_simreel(base + (d / "a").string() + " -o " + (d / "a.gif").string()).code, 0);
  ASSERT_EQ(run_simreel(base + (d / "b").string() + " -o " + (d / "b.gif").string() + " --sync-writes").code, 0);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(slurp(d / "a" / frame_name(i)), slurp(d / "b" / frame_name(i))) << i;
  EXPECT_EQ(slurp(d / "a.gif"), slurp(d / "b.gif"));
}

TEST(Cli, WebmGifContactSheetAndOverlay) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const auto r = run_simreel("render " + (d / "s.json").string() + " -q --size 96x54 --frames 10 -o " +
                             (d / "p").string() + " -o " + (d / "v.gif").string() + " -o " + (d / "v.webm").string() +
                             " --overlay --contact-sheet " + (d / "sheet.png").string() + " --sheet 3x2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(probe(d / "v.gif", "stream=codec_name,nb_read_frames"), "gif,10");
  EXPECT_EQ(probe(d / "v.webm", "stream=codec_name,width,height,nb_read_frames"), "vp9,96,54,10");
  EXPECT_EQ(slurp(d / "sheet.png").substr(1, 3), "PNG");
  // --overlay writes the label into the top-left corner and leaves the rest of the frame alone.
  const auto shown = simreel::render::read_image(d / "p" / frame_name(10 - 1));
  ASSERT_EQ(run_simreel("render " + (d / "s.json").string() + " -q --size 96x54 --frames 9:10 -o " +
                        (d / "clean").string()).code,
            0);
  const auto clean = simreel::render::read_image(d / "clean" / frame_name(9));
  int label = 0, elsewhere = 0;
  for (int y = 0; y < clean.height; ++y) {
    for (int x = 0; x < clean.width; ++x) {
      if (std::memcmp(shown.pixel(x, y), clean.pixel(x, y), 4) == 0) continue;
      (y < 14 ? label : elsewhere) += 1;
    }
  }
  EXPECT_GT(label, 100) << "the label is drawn";
  EXPECT_EQ(elsewhere, 0) << "nothing else changes";
}

TEST(Cli, BadOutputOptionsExit2) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const std::string base = "render " + (d / "s.json").string() + " -q --frames 2 --size 32x32 ";
  auto r = run_simreel(base + "--contact-sheet " + (d / "s.jpg").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--contact-sheet"), std::string::npos) << r.err;
  r = run_simreel(base + "--contact-sheet " + (d / "s.png").string() + " --sheet 0x3");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--sheet 0x3"), std::string::npos) << r.err;
  r = run_simreel(base + "-o " + (d / "v.mp4").string() + " --bitrate fast");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--bitrate fast"), std::string::npos) << r.err;
  r = run_simreel(base + "-o " + (d / "v.mp4").string() + " --crf 60");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--crf 60: expected 0..51 for H.264"), std::string::npos) << r.err;
  r = run_simreel(base + "-o " + (d / "v.avi").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(d / "v.mp4"));
  // An output under a regular file is refused before anything is simulated (it failed with
  // exit 1 once the run was under way), whichever command writes it.
  write_file(d / "notes.txt", "not a folder");
  const std::string under = (d / "notes.txt").string();
  const std::string scene = (d / "s.json").string();
  for (const std::string& args :
       {base + "-o " + under + "/frames", base + "-o " + under + "/deeper/v.mp4",
        base + "-o " + (d / "f").string() + " --contact-sheet " + under + "/s.png",
        base + "-o " + (d / "f").string() + " --hash " + under + "/h.json",
        "bake " + scene + " -q --frames 2 --cache " + under + "/cache",
        "simulate " + scene + " --frames 2 --export " + under + "/p.csv", "schema -o " + under + "/s.json"}) {
    r = run_simreel(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find(under + " is a regular file, expected a folder"), std::string::npos) << args << ": " << r.err;
  }
  EXPECT_FALSE(fs::exists(d / "f"));
  // --hash-every in the range `check` reads back from the golden (CLI11's own check had printed
  // "Value 0 not in range 0.000000 to 1797693134862315708...").
  for (const std::string every : {"0", "1000001"}) {
    r = run_simreel(base + "-o " + (d / "f").string() + " --hash " + (d / "h.json").string() + " --hash-every " + every);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--hash-every " + every + ": expected an integer in [1, 1000000]"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(d / "h.json"));
}

// Ctrl-C: the frame being made is finished, the video closed so it plays, exit 130.
TEST(Cli, InterruptClosesTheVideoAndExits130) {
  TempDir d;
  write_file(d / "s.json", kSmallScene);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    simreel::test::default_signals_for_child();
    const std::string out = (d / "err.txt").string();
    freopen("/dev/null", "w", stdout);
    freopen(out.c_str(), "w", stderr);
    const std::string scene = (d / "s.json").string(), png = (d / "png").string(), mp4 = (d / "v.mp4").string();
    execl(SIMREEL_BIN, SIMREEL_BIN, "render", scene.c_str(), "-q", "--frames", "100000", "--size", "96x54", "-o",
          png.c_str(), "-o", mp4.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait (bounded) until a few frames exist, then interrupt.
  for (int i = 0; i < 600 && !fs::exists(d / "png" / frame_name(3)); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(fs::exists(d / "png" / frame_name(3)));
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed instead of exiting";
  EXPECT_EQ(WEXITSTATUS(status), 130) << slurp(d / "err.txt");
  EXPECT_NE(slurp(d / "err.txt").find("interrupted"), std::string::npos);
  ASSERT_TRUE(fs::exists(d / "v.mp4"));
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(d / "png")) pngs += e.path().extension() == ".png" ? 1 : 0;
  // Every frame handed to the writers is in the video too.
  EXPECT_EQ(probe(d / "v.mp4", "stream=codec_name,nb_read_frames"), "h264," + std::to_string(pngs));
  for (const auto& e : fs::recursive_directory_iterator(d.path))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// ---------------------------------------------------------------------------------------------
// Hash records and `simreel check`

struct Recorded {
  TempDir d;
  fs::path golden;
};


/// Records hashes of frames 0, 4, 8, 12 at 96x72 and their reference frames.
void record(Recorded& r) {
  write_file(r.d / "s.json", kGoldenScene);
  r.golden = r.d / "g.json";
  const auto rec = run_simreel("render " + (r.d / "s.json").string() + " -q --size 96x72 --frames 0:13 --hash-every 4 "
                               "--set /seed=4 --hash " + r.golden.string());
  ASSERT_EQ(rec.code, 0) << rec.err;
  const auto up = run_simreel("check " + r.golden.string() + " --update");
  ASSERT_EQ(up.code, 0) << up.err;
}

TEST(Check, HashRecordDescribesTheRunAndMatchesItself) {
  Recorded r;
  record(r);
  if (HasFatalFailure()) return;
  const auto j = nlohmann::json::parse(slurp(r.golden));
  EXPECT_EQ(j.at("simreel_hashes"), 2);
  EXPECT_EQ(j.at("scene"), "s.json") << "relative to the golden's folder";
  EXPECT_EQ(j.at("size"), "96x72");
  EXPECT_EQ(j.at("frames"), "0:13");
  EXPECT_EQ(j.at("seed"), 4) << "the seed after --set";
  EXPECT_EQ(j.at("set"), nlohmann::json::array({"/seed=4"}));
  EXPECT_FALSE(j.at("gl_renderer").get<std::string>().empty());
  EXPECT_FALSE(j.at("simreel_version").get<std::string>().empty());
  ASSERT_EQ(j.at("hashes").size(), 4u);
  EXPECT_EQ(j.at("hashes")[2].at("frame"), 8);
  EXPECT_EQ(j.at("hashes")[2].at("chash").get<std::string>().size(), 16u);
  for (const char* f : {"00000.png", "00004.png", "00008.png", "00012.png"}) EXPECT_TRUE(fs::exists(r.d / "g.frames" / f)) << f;
  const auto c = run_simreel("check " + r.golden.string());
  EXPECT_EQ(c.code, 0) << c.out << c.err;
  EXPECT_NE(c.out.find("4 frames match"), std::string::npos) << c.out;
}

TEST(Check, ChangedEffectFailsNamesWorstFramesAndWritesComparisons) {
  Recorded r;
  record(r);
  if (HasFatalFailure()) return;
  auto j = nlohmann::json::parse(slurp(r.golden));
  j["set"].push_back("/emitters/0/rate=0");  // the jet is gone
  write_file(r.golden, j.dump(2));
  const auto c = run_simreel("check " + r.golden.string() + " --out " + (r.d / "diff").string());
  EXPECT_EQ(c.code, 1) << c.out << c.err;
  EXPECT_NE(c.out.find("MISMATCH"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("worst: frame 12"), std::string::npos) << c.out;
  ASSERT_TRUE(fs::exists(r.d / "diff" / "frame_00012.png"));
  const auto comparison = simreel::render::read_image(r.d / "diff" / "frame_00012.png");
  EXPECT_EQ(comparison.width, 3 * 96 + 8) << "expected | actual | difference";
  EXPECT_FALSE(fs::exists(r.d / "diff" / "frame_00000.png")) << "frame 0 has no particles yet, so it matches";
  // A generous tolerance accepts it.
  EXPECT_EQ(run_simreel("check " + r.golden.string() + " --tolerance 64").code, 0);
}

TEST(Check, BadGoldenExits2WithPointer) {
  TempDir d;
  write_file(d / "g.json", R"({"simreel_hashes": 1, "scene": "demos/scenes/fountain.json", "size": "96x72",
    "frames": "0:9", "hash_every": 4, "hashes": [{"frame": 3, "phash": "zz", "dhash": "0000000000000000",
    "chash": "0000000000000000"}], "tolerence": 3})");
  const auto c = run_simreel("check " + (d / "g.json").string());
  EXPECT_EQ(c.code, 2);
  EXPECT_NE(c.err.find("/hashes/0/frame"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("/hashes/0/phash: expected 16 hex digits"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("did you mean \"tolerance\""), std::string::npos) << c.err;
  EXPECT_EQ(run_simreel("check " + (d / "missing.json").string()).code, 2);
}

TEST(Golden, EveryDemoSceneHasAGolden) {
  for (const auto& entry : fs::directory_iterator(fs::path(SIMREEL_SOURCE_DIR) / "demos/scenes")) {
    if (entry.path().extension() != ".json") continue;
    const fs::path golden = fs::path(SIMREEL_SOURCE_DIR) / "tests/golden" / entry.path().filename();
    EXPECT_TRUE(fs::exists(golden)) << "record one: see README \"Image-hash regression testing\"; missing " << golden;
  }
}

// The dominoes golden (bodies[i], issue 12) must be able to fail with its bodies frozen: every
// body made static (its dynamic keys dropped) through one "set" of /bodies.
TEST(Golden, DominoesGoldenCatchesFrozenBodies) {
  const fs::path src(SIMREEL_SOURCE_DIR);
  auto golden = nlohmann::json::parse(slurp(src / "tests/golden/dominoes.json"));
  auto bodies = nlohmann::json::parse(slurp(src / "demos/scenes/dominoes.json"))["bodies"];
  for (auto& b : bodies) {
    b.erase("density");
    b.erase("angular_velocity_deg");
    b["type"] = "static";
  }
  TempDir d;
  golden["scene"] = (src / "demos/scenes/dominoes.json").string();
  write_file(d / "g.json", golden.dump(2));
  const auto same = run_simreel("check --allow-outside " + (d / "g.json").string());
  EXPECT_EQ(same.code, 0) << same.out << same.err;
  golden["set"].push_back("/bodies=" + bodies.dump());
  write_file(d / "g.json", golden.dump(2));
  const auto frozen = run_simreel("check --allow-outside " + (d / "g.json").string());
  EXPECT_EQ(frozen.code, 1) << frozen.out << frozen.err;
}

// The project's fountain golden must be able to fail: without the jet (luminance hashes), and
// with the jet's colour ramp turned from blue to red at about the same brightness, which only
// the colour hash sees.
TEST(Golden, FountainGoldenCatchesARemovedJetAndARecolouredRamp) {
  const auto golden = nlohmann::json::parse(slurp(fs::path(SIMREEL_SOURCE_DIR) / "tests/golden/fountain.json"));
  TempDir d;
  auto variant = [&](const std::string& set) {
    auto j = golden;
    j["set"].push_back(set);
    write_file(d / "g.json", j.dump(2));
    return run_simreel("check " + (d / "g.json").string());
  };
  const auto no_jet = variant("/emitters/0/rate=0");
  EXPECT_EQ(no_jet.code, 1) << no_jet.out << no_jet.err;
  const auto red = variant(R"(/emitters/0/color_over_lifetime=[{"t":0,"color":[1.0,0.55,0.45,0.95]},{"t":1,"color":[1.0,0.6,0.5,0.0]}])");
  EXPECT_EQ(red.code, 1) << red.out << red.err;
  // Every failing frame fails on chash alone: pHash and dHash stay within their tolerance.
  std::istringstream lines(red.out);
  int failing = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.find("MISMATCH") == std::string::npos) continue;
    ++failing;
    int frame = 0, p = 0, dh = 0, c = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "frame %d: phash %d  dhash %d  chash %d", &frame, &p, &dh, &c), 4) << line;
    EXPECT_LE(p, golden["tolerance"]["phash"].get<int>()) << line;
    EXPECT_LE(dh, golden["tolerance"]["dhash"].get<int>()) << line;
    EXPECT_GT(c, golden["tolerance"]["chash"].get<int>()) << line;
  }
  EXPECT_GE(failing, 1) << red.out;
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
