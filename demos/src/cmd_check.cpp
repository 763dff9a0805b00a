// `simreel check`: re-render what a golden hash record describes and compare the frames'
// hashes; --update rewrites the golden and its reference frames.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "golden.hpp"
#include "json_reader.hpp"
#include "run_options.hpp"
#include "scene_player.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/image_hash.hpp"
#include "simreel/render/text_overlay.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

/// expected | actual | difference (x4), labelled, at the expected frame's size.
render::Image comparison_image(const render::Image* expected, const render::Image& actual_full) {
  const int w = expected != nullptr ? expected->width : actual_full.width;
  const int h = expected != nullptr ? expected->height : actual_full.height;
  const render::Image actual =
      actual_full.width == w && actual_full.height == h ? actual_full : render::resize_box(actual_full, w, h);
  render::Image out(3 * w + 8, h);
  for (std::size_t i = 0; i < out.rgba.size(); i += 4) {
    out.rgba[i] = out.rgba[i + 1] = out.rgba[i + 2] = 40;
    out.rgba[i + 3] = 255;
  }
  render::Image diff(w, h);
  if (expected != nullptr) {
    render::blit(out, *expected, 0, 0);
    for (std::size_t i = 0; i < diff.rgba.size(); i += 4) {
      for (int c = 0; c < 3; ++c) {
        const int d = std::abs(int(expected->rgba[i + std::size_t(c)]) - int(actual.rgba[i + std::size_t(c)]));
        diff.rgba[i + std::size_t(c)] = std::uint8_t(std::min(255, 4 * d));
      }
      diff.rgba[i + 3] = 255;
    }
  }
  render::blit(out, actual, w + 4, 0);
  render::blit(out, diff, 2 * w + 8, 0);
  render::TextStyle style;
  style.scale = std::max(1, h / 180);
  render::draw_text(out, 0, 0, expected != nullptr ? "expected" : "expected: no reference frame", style);
  render::draw_text(out, w + 4, 0, "actual", style);
  render::draw_text(out, 2 * w + 8, 0, "difference x4", style);
  return out;
}

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

/// The scene a golden names: relative to the golden's folder (or absolute), and it must resolve
/// inside that folder (no "..", no symbolic link out) unless allow_outside. Goldens recorded
/// before this rule name scenes relative to the working directory, which is used when the file
/// is not beside the golden but is there and the path neither is absolute nor climbs.
fs::path golden_scene_path(const fs::path& golden, const std::string& scene, bool allow_outside) {
  const fs::path named(scene);
  const fs::path folder = golden.parent_path().empty() ? fs::path(".") : golden.parent_path();
  fs::path path = named.is_absolute() ? named : folder / named;
  if (allow_outside) return path;
  std::error_code ec;
  if (!fs::exists(path, ec) && stays_below(named) && fs::exists(named, ec)) return named;
  const fs::path real_folder = fs::weakly_canonical(folder, ec);
  const fs::path real = fs::weakly_canonical(path, ec);
  const fs::path rel = real.lexically_relative(real_folder);
  if (ec || rel.empty() || !stays_below(rel))
    throw SceneError(golden.string() + ": /scene: \"" + scene + "\" resolves to " + real.string() +
                     ", outside the golden's folder " + real_folder.string() +
                     "; expected a scene inside it, or pass --allow-outside");
  return path;
}

}  // namespace

int check_command(const CheckOptions& o) {
  const fs::path golden_path(o.golden);
  HashRecord golden = read_hash_record(golden_path);
  if (o.tolerance) golden.tolerance = {*o.tolerance, *o.tolerance, *o.tolerance};
  RunOptions run;
  run.scene = golden_scene_path(golden_path, golden.scene, o.allow_outside).string();
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
      throw SceneError(o.golden + ": /scene: " + run.scene + " is not a valid scene (" +
                       std::to_string(e.messages().size()) + " error(s), not shown: run `simreel validate " +
                       run.scene + "` to see them)");
    }
  }();
  if (!o.update && golden.frames.empty())
    throw SceneError(o.golden + ": /hashes: the golden holds no hashes; record them with --update");

  ScenePlayer player(scene);
  const fs::path frames_dir = golden_frames_dir(golden_path);
  std::vector<FrameHashes> actual;
  struct Mismatch {
    int frame;
    int distance[3];
    int excess;
  };
  std::vector<Mismatch> mismatches;
  std::vector<int> wanted;
  if (o.update) {
    for (int f = golden.first; f < golden.end; f += golden.every) wanted.push_back(f);
  } else {
    for (const FrameHashes& f : golden.frames) wanted.push_back(f.frame);
    std::sort(wanted.begin(), wanted.end());
  }
  std::vector<fs::path> written;
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
    const int d[3] = {render::hamming(h.phash, it->phash), render::hamming(h.dhash, it->dhash),
                      render::hamming(h.chash, it->chash)};
    const int tol[3] = {golden.tolerance.phash, golden.tolerance.dhash, golden.tolerance.chash};
    int excess = 0;
    for (int k = 0; k < 3; ++k) excess = std::max(excess, d[k] - tol[k]);
    if (excess > 0) {
      mismatches.push_back({frame, {d[0], d[1], d[2]}, excess});
      std::cout << "frame " << frame << ": phash " << d[0] << "  dhash " << d[1] << "  chash " << d[2]
                << "  (tolerance " << tol[0] << "/" << tol[1] << "/" << tol[2] << ")  MISMATCH\n";
      if (!o.out_dir.empty()) {
        std::optional<render::Image> expected;
        const fs::path ref = frames_dir / frame_png_name(frame);
        if (fs::exists(ref)) expected = render::read_image(ref);
        fs::create_directories(o.out_dir);
        const fs::path target = fs::path(o.out_dir) / ("frame_" + frame_png_name(frame));
        render::write_png(target, comparison_image(expected ? &*expected : nullptr, image), 6);
        written.push_back(target);
      }
    } else {
      std::cout << "frame " << frame << ": phash " << d[0] << "  dhash " << d[1] << "  chash " << d[2] << "  ok\n";
    }
  }
  const std::string machine = player.context().renderer_string() + ", OpenGL " + player.context().version_string();

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
        const std::string name = e.path().filename().string();
        const bool kept = std::any_of(actual.begin(), actual.end(),
                                      [&](const FrameHashes& f) { return frame_png_name(f.frame) == name; });
        if (!kept && e.path().extension() == ".png") fs::remove(e.path());
      }
    }
    write_file_atomic(golden_path, to_json(golden).dump(2) + "\n");
    std::cout << "updated " << o.golden << " (" << actual.size() << " frames) and reference frames in "
              << frames_dir.string() << "/ on " << machine << "\n";
    return 0;
  }
  if (mismatches.empty()) {
    std::cout << o.golden << ": " << actual.size() << " frames match\n";
    return 0;
  }
  std::sort(mismatches.begin(), mismatches.end(),
            [](const Mismatch& a, const Mismatch& b) { return a.excess > b.excess || (a.excess == b.excess && a.frame < b.frame); });
  std::cout << o.golden << ": " << mismatches.size() << " of " << actual.size()
            << " frames out of tolerance; worst:";
  for (std::size_t i = 0; i < std::min<std::size_t>(5, mismatches.size()); ++i) {
    const Mismatch& m = mismatches[i];
    std::cout << (i == 0 ? " " : ", ") << "frame " << m.frame << " (phash " << m.distance[0] << ", dhash "
              << m.distance[1] << ", chash " << m.distance[2] << ")";
  }
  std::cout << "\nrecorded on " << golden.gl_renderer << ", OpenGL " << golden.gl_version << "; this run on "
            << machine << "\n";
  if (!written.empty()) {
    std::cout << "expected | actual | difference images:";
    for (const auto& p : written) std::cout << " " << p.string();
    std::cout << "\n";
  }
  return 1;
}

}  // namespace simreel::app
