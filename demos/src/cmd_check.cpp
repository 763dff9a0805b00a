// `simreel check`: re-render what golden hash records describe and compare the frames' hashes;
// --update rewrites the goldens and their reference frames; --junit and --report tell CI.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <cstring>
#include <sstream>

#include "check_report.hpp"
#include "commands.hpp"
#include "golden.hpp"
#include "json_reader.hpp"
#include "run_options.hpp"
#include "scene_player.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/image_hash.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

std::string frame_png_name(int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%05d.png", frame);
  return name;
}

/// True when `p` (relative) has no ".." component: it cannot climb out of its base.
bool stays_below(const fs::path& p) {
  if (p.is_absolute() || p.has_root_name() || p.has_root_directory()) return false;
  return std::none_of(p.begin(), p.end(), [](const fs::path& part) { return part == ".."; });
}

/// True when `real` (canonical) lies inside the folder `root` (resolved here).
bool inside(const fs::path& real, const fs::path& root) {
  std::error_code ec;
  const fs::path real_root = fs::weakly_canonical(root, ec);
  if (ec) return false;
  const fs::path rel = real.lexically_relative(real_root);
  return !rel.empty() && stays_below(rel);
}

/// The scene a golden names. Format 2: relative to the golden's folder (or absolute); it must
/// resolve (symbolic links followed) inside the golden's folder, the working directory or a
/// --root folder, unless allow_outside. Format 1 (older goldens, recorded with the path given to
/// `render`): beside the golden if there, else relative to the working directory, and it must
/// not leave the golden's folder or climb out of the working directory.
fs::path golden_scene_path(const fs::path& golden, const HashRecord& record, const CheckOptions& o) {
  const std::string& scene = record.scene;
  const fs::path named(scene);
  const fs::path folder = golden.parent_path().empty() ? fs::path(".") : golden.parent_path();
  fs::path path = named.is_absolute() ? named : folder / named;
  if (o.allow_outside) return path;
  std::error_code ec;
  if (record.format == 1 && !fs::exists(path, ec) && stays_below(named) && fs::exists(named, ec)) return named;
  std::error_code real_ec;
  const fs::path real = fs::weakly_canonical(path, real_ec);
  bool allowed = !real_ec && inside(real, folder);
  std::vector<std::string> trusted = {"the golden's folder " + fs::weakly_canonical(folder, ec).string()};
  if (record.format >= 2) {
    allowed = allowed || (!real_ec && inside(real, fs::current_path()));
    trusted.push_back("the working directory");
    for (const auto& root : o.roots) {
      allowed = allowed || (!real_ec && inside(real, root));
      trusted.push_back("--root " + root);
    }
  }
  if (!allowed) {
    std::string where;
    for (std::size_t i = 0; i < trusted.size(); ++i)
      where += (i == 0 ? "" : i + 1 == trusted.size() ? " or " : ", ") + trusted[i];
    throw SceneError(golden.string() + ": /scene: \"" + scene + "\" resolves to " + real.string() +
                     ", outside the golden's folder; expected a scene inside " + where +
                     (record.format >= 2 ? "; pass --root DIR to trust DIR" : "") + ", or pass --allow-outside");
  }
  // Only now, inside the trusted folders, may the answer depend on what exists.
  if (!fs::exists(path, ec)) {
    const std::string where = record.format == 1
                                  ? " (format 1: looked beside the golden, at " + path.string() +
                                        ", and from the working directory; run check where `render --hash` ran, "
                                        "or record the golden again)"
                                  : " (relative to the golden's folder: " + path.string() + ")";
    throw SceneError(golden.string() + ": /scene: \"" + scene + "\": no such file" + where);
  }
  return path;
}

/// The goldens named by `paths`: files as given, folders searched recursively (in name order)
/// for JSON files that hold "simreel_hashes"; reference-frame folders (*.frames) are skipped.
/// @throws SceneError for a path that does not exist or a folder without goldens.
std::vector<fs::path> collect_goldens(const std::vector<std::string>& paths) {
  std::vector<fs::path> out;
  for (const std::string& p : paths) {
    std::error_code ec;
    if (!fs::is_directory(p, ec)) {
      out.emplace_back(p);  // read_hash_record names a missing or unreadable file
      continue;
    }
    std::vector<fs::path> found;
    for (auto it = fs::recursive_directory_iterator(p, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec)) {
      if (it->is_directory() && it->path().extension() == ".frames") {
        it.disable_recursion_pending();
        continue;
      }
      if (!it->is_regular_file() || it->path().extension() != ".json") continue;
      if (it->file_size() > kMaxJsonBytes) continue;
      try {
        const std::string text = read_regular_file(it->path(), "golden", kMaxJsonBytes);
        if (text.find("\"simreel_hashes\"") != std::string::npos) found.push_back(it->path());
      } catch (const SceneError&) {
        // Unreadable: not a golden this search can know of.
      }
    }
    if (ec) throw SceneError(p + ": cannot search the folder: " + ec.message());
    if (found.empty())
      throw SceneError(p + ": no goldens found (JSON files with \"simreel_hashes\", written by `simreel render --hash`)");
    std::sort(found.begin(), found.end());
    out.insert(out.end(), found.begin(), found.end());
  }
  return out;
}

/// Checks (or updates) one golden; prints its frame lines. Bad input throws SceneError.
GoldenOutcome check_one(const fs::path& golden_path, const CheckOptions& o, const fs::path& out_dir,
                        const fs::path& report_dir) {
  GoldenOutcome result;
  result.golden = golden_path.string();
  const std::string& name = result.golden;
  HashRecord golden = read_hash_record(golden_path);
  if (o.tolerance) golden.tolerance = {*o.tolerance, *o.tolerance, *o.tolerance};
  RunOptions run;
  run.scene = golden_scene_path(golden_path, golden, o).string();
  run.overrides = golden.overrides;
  run.frames = std::to_string(golden.first) + ":" + std::to_string(golden.end);
  run.fps = golden.fps;
  run.size = std::to_string(golden.width) + "x" + std::to_string(golden.height);
  run.seed = golden.seed;
  run.backend = o.backend ? *o.backend : golden.backend;
  run.renders = true;
  int first = 0;
  // The golden may be untrusted (a pull request): the file it names might be no scene at all,
  // so its values are never echoed; `simreel validate` shows them to whoever wants to look.
  const Scene scene = [&] {
    try {
      return prepare_scene(run, &first);
    } catch (const SceneError& e) {
      // The golden's own overrides go into the command: without them `validate` may pass a
      // scene that only an override (a key the scene lacks, a value out of range) breaks.
      const auto quoted = [](const std::string& a) {
        const bool plain = !a.empty() && std::all_of(a.begin(), a.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) != 0 || std::strchr("_./:=+-@%,", c) != nullptr;
        });
        if (plain) return a;
        std::string q = "'";
        for (const char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
        return q + "'";
      };
      std::string command = "simreel validate " + quoted(run.scene);
      for (const std::string& o : run.overrides) command += " --set " + quoted(o);
      throw SceneError(name + ": /scene: " + run.scene + " is not a valid scene" +
                       (run.overrides.empty() ? "" : " with the golden's /set overrides") + " (" +
                       std::to_string(e.messages().size()) + " error(s), not shown: run `" + command +
                       "` to see them)");
    }
  }();
  if (!o.update && golden.frames.empty())
    throw SceneError(name + ": /hashes: the golden holds no hashes; record them with --update");

  ScenePlayer player(scene);
  const fs::path frames_dir = golden_frames_dir(golden_path);
  std::vector<FrameHashes> actual;
  std::vector<int> wanted;
  if (o.update) {
    for (int f = golden.first; f < golden.end; f += golden.every) wanted.push_back(f);
  } else {
    for (const FrameHashes& f : golden.frames) wanted.push_back(f.frame);
    std::sort(wanted.begin(), wanted.end());
  }
  std::vector<fs::path> written;
  std::ostringstream details;
  const std::string report_sub = report_folder_name(name);
  for (const int frame : wanted) {
    player.advance_to(frame);
    const render::Image image = player.render();
    const FrameHashes h = hash_frame(image, frame);
    actual.push_back(h);
    if (o.update) {
      render::Image thumb = image;
      if (image.width > 320) thumb = render::resize_box(image, 320, std::max(1, image.height * 320 / image.width));
      fs::create_directories(frames_dir);
      render::write_png(frames_dir / frame_png_name(frame), thumb, 9);
      continue;
    }
    const auto it = std::find_if(golden.frames.begin(), golden.frames.end(),
                                 [&](const FrameHashes& g) { return g.frame == frame; });
    FrameMismatch m;
    m.frame = frame;
    m.distance[0] = render::hamming(h.phash, it->phash);
    m.distance[1] = render::hamming(h.dhash, it->dhash);
    m.distance[2] = render::hamming(h.chash, it->chash);
    m.tolerance[0] = golden.tolerance.phash;
    m.tolerance[1] = golden.tolerance.dhash;
    m.tolerance[2] = golden.tolerance.chash;
    for (int k = 0; k < 3; ++k) m.excess = std::max(m.excess, m.distance[k] - m.tolerance[k]);
    const bool bad = m.excess > 0;
    char line[160];
    std::snprintf(line, sizeof line, "frame %d: phash %d  dhash %d  chash %d", frame, m.distance[0], m.distance[1],
                  m.distance[2]);
    std::string text = line;
    if (bad) {
      std::snprintf(line, sizeof line, "  (tolerance %d/%d/%d)  MISMATCH", m.tolerance[0], m.tolerance[1],
                    m.tolerance[2]);
      text += line;
    } else {
      text += "  ok";
    }
    std::cout << text << "\n";
    details << text << "\n";
    if (!bad) continue;
    std::optional<render::Image> expected;
    const fs::path ref = frames_dir / frame_png_name(frame);
    if (fs::exists(ref)) expected = render::read_image(ref);
    if (!out_dir.empty()) {
      const fs::path target = out_dir / ("frame_" + frame_png_name(frame));
      render::write_png(target, comparison_image(expected ? &*expected : nullptr, image), 6);
      written.push_back(target);
    }
    if (!report_dir.empty()) {
      // The actual frame at the reference frame's size, so the three line up.
      const render::Image shown =
          expected && (expected->width != image.width || expected->height != image.height)
              ? render::resize_box(image, expected->width, expected->height)
              : image;
      const std::string stem = report_sub + "/frame_" + std::to_string(frame);
      m.actual_png = stem + "_actual.png";
      render::write_png(report_dir / m.actual_png, shown, 6);
      if (expected) {
        m.expected_png = stem + "_expected.png";
        m.diff_png = stem + "_difference.png";
        render::write_png(report_dir / m.expected_png, *expected, 6);
        render::write_png(report_dir / m.diff_png, difference_image(*expected, shown), 6);
      }
    }
    result.mismatches.push_back(m);
  }
  const std::string machine = player.context().renderer_string() + ", OpenGL " + player.context().version_string();
  result.frames = int(actual.size());

  if (o.update) {
    golden.frames = actual;
    golden.simreel_version = SIMREEL_VERSION;
    golden.backend = player.context().backend_name();
    golden.gl_renderer = player.context().renderer_string();
    golden.gl_version = player.context().version_string();
    if (o.tolerance) golden.tolerance = {*o.tolerance, *o.tolerance, *o.tolerance};
    // Reference frames no longer hashed would mislead the next review.
    if (fs::is_directory(frames_dir)) {
      for (const auto& e : fs::directory_iterator(frames_dir)) {
        const std::string file = e.path().filename().string();
        const bool kept = std::any_of(actual.begin(), actual.end(),
                                      [&](const FrameHashes& f) { return frame_png_name(f.frame) == file; });
        if (!kept && e.path().extension() == ".png") fs::remove(e.path());
      }
    }
    write_file_atomic(golden_path, to_json(golden).dump(2) + "\n");
    std::cout << "updated " << name << " (" << actual.size() << " frames) and reference frames in "
              << frames_dir.string() << "/ on " << machine << "\n";
    result.status = GoldenOutcome::Status::updated;
    return result;
  }
  if (result.mismatches.empty()) {
    std::cout << name << ": " << actual.size() << " frames match\n";
    result.status = GoldenOutcome::Status::passed;
    return result;
  }
  auto& mm = result.mismatches;
  std::sort(mm.begin(), mm.end(), [](const FrameMismatch& a, const FrameMismatch& b) {
    return a.excess > b.excess || (a.excess == b.excess && a.frame < b.frame);
  });
  std::ostringstream msg;
  msg << mm.size() << " of " << actual.size() << " frames out of tolerance; worst:";
  for (std::size_t i = 0; i < std::min<std::size_t>(5, mm.size()); ++i) {
    const FrameMismatch& m = mm[i];
    msg << (i == 0 ? " " : ", ") << "frame " << m.frame << " (phash " << m.distance[0] << ", dhash " << m.distance[1]
        << ", chash " << m.distance[2] << ")";
  }
  const std::string machines =
      "recorded on " + golden.gl_renderer + ", OpenGL " + golden.gl_version + "; this run on " + machine;
  result.status = GoldenOutcome::Status::failed;
  result.message = msg.str() + " (tolerance " + std::to_string(golden.tolerance.phash) + "/" +
                   std::to_string(golden.tolerance.dhash) + "/" + std::to_string(golden.tolerance.chash) + ")";
  result.details = details.str() + machines + "\n";
  std::cout << name << ": " << msg.str() << "\n" << machines << "\n";
  if (!written.empty()) {
    std::cout << "expected | actual | difference images:";
    for (const auto& p : written) std::cout << " " << p.string();
    std::cout << "\n";
  }
  return result;
}

}  // namespace

int check_command(const CheckOptions& o) {
  if (!o.junit.empty() && fs::path(o.junit).extension() != ".xml")
    throw SceneError("--junit " + o.junit + ": expected a .xml file");
  for (const auto& root : o.roots) {
    std::error_code ec;
    if (!fs::is_directory(root, ec)) throw SceneError("--root " + root + ": expected a folder");
  }
  check_outputs({{"--junit", o.junit, false}, {"--report", o.report_dir, true}});
  const std::vector<fs::path> goldens = collect_goldens(o.goldens);
  const bool several = goldens.size() > 1;
  std::vector<GoldenOutcome> outcomes;
  for (const fs::path& golden : goldens) {
    if (several) std::cout << "== " << golden.string() << "\n";
    const auto start = std::chrono::steady_clock::now();
    GoldenOutcome outcome;
    try {
      fs::path out_dir = o.out_dir;
      if (!out_dir.empty() && several) out_dir /= report_folder_name(golden.string());
      outcome = check_one(golden, o, out_dir, o.report_dir);
    } catch (const SceneError& e) {
      for (const auto& m : e.messages()) std::cerr << "simreel: error: " << m << "\n";
      outcome.golden = golden.string();
      outcome.status = GoldenOutcome::Status::error;
      outcome.message = e.messages().empty() ? "bad golden" : e.messages().front();
      for (const auto& m : e.messages()) outcome.details += m + "\n";
    }
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    outcomes.push_back(std::move(outcome));
  }
  if (!o.junit.empty()) write_junit(o.junit, outcomes);
  if (!o.report_dir.empty()) write_html_report(o.report_dir, outcomes);
  std::cout << summary_line(outcomes) << "\n";
  if (!o.junit.empty()) std::cout << "wrote " << o.junit << "\n";
  if (!o.report_dir.empty()) std::cout << "wrote " << (fs::path(o.report_dir) / "index.html").string() << "\n";
  using S = GoldenOutcome::Status;
  const auto any = [&](S s) {
    return std::any_of(outcomes.begin(), outcomes.end(), [s](const GoldenOutcome& g) { return g.status == s; });
  };
  if (any(S::error)) return 2;
  return any(S::failed) ? 1 : 0;
}

}  // namespace simreel::app
