// The workflow around the engine, as a user runs it: `check` over several goldens with a summary,
// JUnit XML and an HTML report; goldens whose scene path is relative to the golden; `presets
// --expand` and the preset errors; `sweep`; `schema`. Tiny frames and few frames keep it fast.
#include <gtest/gtest.h>

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

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }



/// Renders `scene` into a golden with frames 0, 4, 8 at 64x48 and records its reference frames.
void record(const fs::path& scene, const fs::path& golden, const std::string& extra = "") {
  const auto rec = run_simreel("render " + scene.string() + " -q --size 64x48 --frames 0:9 --hash-every 4 --hash " +
                               golden.string());
  ASSERT_EQ(rec.code, 0) << rec.err;
  const auto up = run_simreel("check " + golden.string() + " --update " + extra);
  ASSERT_EQ(up.code, 0) << up.out << up.err;
}

}  // namespace

// --- check ----------------------------------------------------------------------------------

TEST(Workflow, NewGoldensNameTheirSceneRelativeToTheGoldenAndCheckFromAnywhere) {
  TempDir d;
  fs::create_directories(d / "goldens" / "scenes");
  write_file(d / "goldens" / "scenes" / "jet.json", kGoldenScene);
  record(d / "goldens" / "scenes" / "jet.json", d / "goldens" / "jet.json");
  if (HasFatalFailure()) return;
  const auto j = nlohmann::json::parse(slurp(d / "goldens" / "jet.json"));
  EXPECT_EQ(j.at("simreel_hashes"), 2);
  EXPECT_EQ(j.at("scene"), "scenes/jet.json");
  // The tests run in the source tree, far from the golden: the scene is still found.
  const auto c = run_simreel("check " + (d / "goldens" / "jet.json").string());
  EXPECT_EQ(c.code, 0) << c.out << c.err;
  EXPECT_TRUE(has(c.out, "1 passed, 0 failed")) << c.out;
}

TEST(Workflow, SceneBesideTheGoldensFolderNeedsRootOrTheWorkingDirectory) {
  TempDir d;
  fs::create_directories(d / "scenes");
  write_file(d / "scenes" / "jet.json", kGoldenScene);
  record(d / "scenes" / "jet.json", d / "goldens" / "jet.json", "--root " + d.path.string());
  if (HasFatalFailure()) return;
  EXPECT_EQ(nlohmann::json::parse(slurp(d / "goldens" / "jet.json")).at("scene"), "../scenes/jet.json");
  // From the source tree, ../scenes is outside both the golden's folder and the working directory.
  const auto refused = run_simreel("check " + (d / "goldens" / "jet.json").string());
  EXPECT_EQ(refused.code, 2) << refused.out << refused.err;
  EXPECT_TRUE(has(refused.err, "--root")) << refused.err;
  const auto c = run_simreel("check " + (d / "goldens").string() + " --root " + d.path.string());
  EXPECT_EQ(c.code, 0) << c.out << c.err;
  // From the folder that holds both (as CI runs from the repository root), no flag is needed.
  const auto here = run_simreel("check goldens", "cd " + d.path.string() + " &&");
  EXPECT_EQ(here.code, 0) << here.out << here.err;
}

TEST(Workflow, CheckSeveralGoldensWritesSummaryJunitAndReport) {
  TempDir d;
  write_file(d / "jet.json", kGoldenScene);
  record(d / "jet.json", d / "a.json");
  if (HasFatalFailure()) return;
  // b: the same golden with the jet removed, so it fails; c: not a golden at all (skipped in a
  // folder search); d/bad.json: a broken golden (an error, not a failure).
  auto b = nlohmann::json::parse(slurp(d / "a.json"));
  b["set"].push_back("/emitters/0/rate=0");
  write_file(d / "b.json", b.dump(2));
  fs::copy(d / "a.frames", d / "b.frames", fs::copy_options::recursive);
  const auto c = run_simreel("check " + d.path.string() + " --junit " + (d / "out" / "junit.xml").string() +
                             " --report " + (d / "out" / "report").string());
  EXPECT_EQ(c.code, 1) << c.out << c.err;
  EXPECT_TRUE(has(c.out, "1 passed, 1 failed")) << c.out;
  const std::string xml = slurp(d / "out" / "junit.xml");
  EXPECT_TRUE(has(xml, "tests=\"2\" failures=\"1\" errors=\"0\"")) << xml;
  EXPECT_TRUE(has(xml, "<failure type=\"mismatch\" message=\"")) << xml;
  EXPECT_TRUE(has(xml, "worst: frame ")) << xml;
  EXPECT_TRUE(has(xml, (d / "a.json").string() + "\" time=")) << xml;
  const std::string html = slurp(d / "out" / "report" / "index.html");
  EXPECT_TRUE(has(html, "1 passed, 1 failed")) << html;
  int images = 0;
  for (const auto& e : fs::recursive_directory_iterator(d / "out" / "report")) {
    if (e.path().extension() != ".png") continue;
    ++images;
    EXPECT_TRUE(has(html, fs::relative(e.path(), d / "out" / "report").string())) << e.path();
    const auto image = simreel::render::read_image(e.path());
    EXPECT_EQ(image.width, 64);
  }
  EXPECT_GE(images, 3) << "expected, actual and difference of at least one frame";
  // A broken golden among them: exit 2, counted as an error, the others still checked.
  write_file(d / "bad.json", R"({"simreel_hashes": 2, "scene": "jet.json", "size": "64x48", "frames": "0:9", "hashes": 3})");
  const auto e = run_simreel("check " + (d / "a.json").string() + " " + (d / "bad.json").string() + " --junit " +
                             (d / "j2.xml").string());
  EXPECT_EQ(e.code, 2) << e.out << e.err;
  EXPECT_TRUE(has(e.out, "1 passed, 0 failed, 1 error")) << e.out;
  EXPECT_TRUE(has(slurp(d / "j2.xml"), "<error type=\"bad input\" message=\"")) << slurp(d / "j2.xml");
  for (const auto& f : fs::recursive_directory_iterator(d.path))
    EXPECT_FALSE(has(f.path().filename().string(), ".tmp-")) << f.path();
}

TEST(Workflow, CheckUsageErrorsExit2WithOneLine) {
  TempDir d;
  fs::create_directories(d / "empty");
  for (const std::string& args : {"check " + (d / "empty").string(), "check " + (d / "missing.json").string(),
                                  "check " + (d / "empty").string() + " --junit out.txt",
                                  "check " + (d / "empty").string() + " --root " + (d / "nope").string()}) {
    const auto r = run_simreel(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << args << ": " << r.err;
  }
  EXPECT_TRUE(has(run_simreel("check " + (d / "empty").string()).err, "no goldens found"));
  // A golden whose scene is missing says so, naming where it looked.
  write_file(d / "g.json", R"({"simreel_hashes": 2, "scene": "nope.json", "size": "64x48", "frames": "0:9", "hashes": []})");
  const auto r = run_simreel("check " + (d / "g.json").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "/scene: \"nope.json\": no such file (relative to the golden's folder: ")) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
}

// --- presets ----------------------------------------------------------------------------------

TEST(Workflow, PresetsExpandPrintsTheDerivedEmittersAsSceneJson) {
  const auto r = run_simreel("presets fire_smoke --expand");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_GE(j.at("emitters").size(), 2u);
  EXPECT_EQ(j["emitters"][0].at("name").get<std::string>().rfind("fire_smoke/", 0), 0u) << r.out;
  // The output is a scene: it validates as it is.
  TempDir d;
  write_file(d / "s.json", r.out);
  const auto v = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(v.code, 0) << v.out << v.err;
  // A knob changes what is derived.
  const auto denser = run_simreel("presets smoke --expand --set density=2.5 --set position=[1,2,0]");
  ASSERT_EQ(denser.code, 0) << denser.err;
  EXPECT_NE(denser.out, run_simreel("presets smoke --expand").out);
  EXPECT_TRUE(has(denser.out, "1.0")) << "the position moved the emitter";
}

TEST(Workflow, PresetErrorsPointToTheFix) {
  // A misspelt knob in --set, a value out of range, a misspelt effect: exit 2, one line each.
  auto r = run_simreel("presets smoke --expand --set densty=2");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "did you mean \"density\"")) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  r = run_simreel("presets smoke --expand --set density=-1");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "/density")) << r.err;
  r = run_simreel("presets smok");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "did you mean \"smoke\"")) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  r = run_simreel("presets smoke --set density=2");
  EXPECT_EQ(r.code, 2) << "--set needs --expand";

  TempDir d;
  // An emitter key on a preset object: put it under "overrides".
  write_file(d / "rate.json", R"({"emitters": [{"effect": "smoke", "rate": 500}]})");
  r = run_simreel("validate " + (d / "rate.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "/emitters/0/rate")) << r.err;
  EXPECT_TRUE(has(r.err, "\"overrides\": {\"rate\": 500}")) << r.err;
  EXPECT_FALSE(has(r.err, "did you mean")) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  // With several derived emitters the hint names their roles.
  write_file(d / "roles.json", R"({"emitters": [{"effect": "fire_smoke", "lifetime": 3}]})");
  r = run_simreel("validate " + (d / "roles.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "one patch per derived emitter")) << r.err;
  // A misspelt effect: the closest effect, not another effect's knobs.
  write_file(d / "smok.json", R"({"emitters": [{"effect": "smok", "density": 1}]})");
  r = run_simreel("validate " + (d / "smok.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "/emitters/0/effect: unknown effect \"smok\"; did you mean \"smoke\"?")) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
}

// --- sweep ------------------------------------------------------------------------------------

TEST(Workflow, SweepRendersEveryCombinationIntoOneLabelledSheet) {
  TempDir d;
  write_file(d / "jet.json", kGoldenScene);
  const std::string base = "sweep " + (d / "jet.json").string() +
                           " --vary /emitters/0/rate=50,1500 --seeds 1,2 --frames 0:6 --size 64x48 --strip 2 ";
  const auto r = run_simreel(base + "--contact-sheet " + (d / "sheet.png").string() + " -o " + (d / "variants").string() +
                             " --hash");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto sheet = simreel::render::read_image(d / "sheet.png");
  // 2 rows (rate) x 2 columns (seed) of 2-frame strips, plus labels.
  EXPECT_GT(sheet.width, 2 * (2 * 64 + 4));
  EXPECT_GT(sheet.height, 2 * 48);
  for (const char* name : {"00_rate-50_seed-1", "01_rate-50_seed-2", "02_rate-1500_seed-1", "03_rate-1500_seed-2"}) {
    EXPECT_TRUE(fs::exists(d / "variants" / (std::string(name) + ".mp4"))) << name << "\n" << r.out;
    EXPECT_TRUE(fs::exists(d / "variants" / (std::string(name) + ".json"))) << name;
  }
  // Each golden re-renders its variant.
  const auto c = run_simreel("check " + (d / "variants").string() + " --root " + d.path.string());
  EXPECT_EQ(c.code, 0) << c.out << c.err;
  EXPECT_TRUE(has(c.out, "4 passed, 0 failed")) << c.out;
  // The sheet does not depend on how many variants run at once.
  const auto one = run_simreel(base + "--jobs 1 --contact-sheet " + (d / "sheet1.png").string());
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_EQ(slurp(d / "sheet1.png"), slurp(d / "sheet.png"));
}

TEST(Workflow, SweepHandsItsFpsToEachVariantExactly) {
  // The children were given std::to_string(fps), six decimals: --fps 23.976023976 rendered every
  // variant (and recorded its golden) at 23.976024 fps, another sampling time than the one asked.
  TempDir d;
  write_file(d / "jet.json", kGoldenScene);
  const auto r = run_simreel("sweep " + (d / "jet.json").string() +
                             " --vary /emitters/0/rate=50 --frames 0:2 --size 64x48 --strip 1 --fps 23.976023976"
                             " --contact-sheet " + (d / "sheet.png").string() + " -o " + (d / "v").string() + " --hash");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto j = nlohmann::json::parse(slurp(d / "v" / "00_rate-50.json"));
  EXPECT_EQ(j.at("fps").get<double>(), 23.976023976) << j.at("fps");
}

TEST(Workflow, SweepRunsNoMoreVariantsAtOnceThanTheMemoryBudgetHolds) {
  // Each variant was checked against the budget alone, and --jobs (default: the cores) of them
  // then ran together: 16 variants of 4K frames on a 16-core machine needed 16 budgets' worth.
  TempDir d;
  write_file(d / "jet.json", kGoldenScene);
  const std::string scene = (d / "jet.json").string(), size = " --frames 0:1 --size 64x48";
  // One variant's estimate, from the message of a budget it does not fit.
  const auto probe = run_simreel("render " + scene + size + " -q --memory-limit 1 -o " + (d / "p").string());
  ASSERT_EQ(probe.code, 2) << probe.err;
  const auto at = probe.err.find("needs about ");
  ASSERT_NE(at, std::string::npos) << probe.err;
  const long mib = std::stol(probe.err.substr(at + 12));
  ASSERT_GT(mib, 0);
  for (const auto& [budget_mib, expected] : {std::pair{mib * 3 / 2, std::string("1 at a time (--jobs 3 lowered")},
                                            std::pair{mib * 5 / 2, std::string("2 at a time (--jobs 3 lowered")},
                                            std::pair{mib * 4, std::string("3 at a time\n")}}) {
    const auto r = run_simreel("sweep " + scene + size + " --vary /emitters/0/rate=50,100,200 --jobs 3 --memory-limit " +
                               std::to_string(budget_mib) + "M --contact-sheet " + (d / "s.png").string());
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(has(r.out, expected)) << budget_mib << " MiB for " << mib << " MiB a variant:\n" << r.out;
  }
}

TEST(Workflow, SweepErrorsExit2BeforeRendering) {
  TempDir d;
  write_file(d / "jet.json", kGoldenScene);
  const std::string scene = (d / "jet.json").string();
  const std::string sheet = " --contact-sheet " + (d / "s.png").string();
  for (const std::string& args :
       {"sweep " + scene + " --vary rate=1,2" + sheet, "sweep " + scene + " --vary /emitters/0/rate=1,fast" + sheet,
        "sweep " + scene + " --vary /emitters/0/rate=1,,2" + sheet, "sweep " + scene + " --vary /nothing/here=1" + sheet,
        "sweep " + scene + " --vary /emitters/0/rate=1,2 --contact-sheet " + (d / "s.jpg").string(),
        "sweep " + scene + " --vary /emitters/0/rate=1,2 --hash" + sheet, "sweep " + scene + " --seeds 1,x" + sheet}) {
    const auto r = run_simreel(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << args << ": " << r.err;
  }
  EXPECT_TRUE(has(run_simreel("sweep " + scene + " --vary /emitters/0/rate=1,fast" + sheet).err,
                  "variant rate=fast: " + scene + ": /emitters/0/rate: expected a number"));
  EXPECT_FALSE(fs::exists(d / "s.png"));
}

// --- schema -----------------------------------------------------------------------------------

TEST(Workflow, SchemaIsDraft2020AndScenesMayNameIt) {
  const auto r = run_simreel("schema");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("$schema"), "https://json-schema.org/draft/2020-12/schema");
  const auto& emitter = j.at("properties").at("emitters").at("items");
  EXPECT_TRUE(emitter.at("else").at("properties").contains("rate"));
  EXPECT_TRUE(has(emitter.at("else").at("properties").at("rate").at("description").get<std::string>(), "particles/s"));
  EXPECT_EQ(emitter.at("then").at("oneOf").size(), 7u) << "one schema per effect preset";
  TempDir d;
  const auto w = run_simreel("schema -o " + (d / "scene.schema.json").string());
  EXPECT_EQ(w.code, 0) << w.err;
  EXPECT_EQ(slurp(d / "scene.schema.json"), r.out);
  write_file(d / "s.json", R"({"$schema": "scene.schema.json", "frames": 2})");
  EXPECT_EQ(run_simreel("validate " + (d / "s.json").string()).code, 0);
  EXPECT_EQ(run_simreel("schema extra").code, 2);
}
