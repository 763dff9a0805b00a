// `simreel render`: simulate a scene and write its frames to PNG sequences, videos, a contact
// sheet and/or a hash record, with progress and a clean stop on Ctrl-C.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <optional>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <utility>

#include "commands.hpp"
#include "golden.hpp"
#include "json_reader.hpp"
#include "run_options.hpp"
#include "signal_scope.hpp"
#include "scene_player.hpp"
#include "sim_cache.hpp"
#include "simreel/render/atomic_file.hpp"
#include "simreel/render/frame_sink.hpp"
#include "simreel/render/text_overlay.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool is_video_path(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".mp4" || ext == ".gif" || ext == ".webm";
}

std::string format_duration(double s) {
  char buf[32];
  if (s >= 3600) std::snprintf(buf, sizeof buf, "%dh%02dm", int(s / 3600), int(s / 60) % 60);
  else if (s >= 60) std::snprintf(buf, sizeof buf, "%dm%02ds", int(s / 60), int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%.1fs", s);
  return buf;
}

volatile std::sig_atomic_t g_stop_signal = 0;

/// The first signal sets the flag; a second is a hard stop: the ffmpeg children are killed and
/// the temporaries removed (async-signal-safe), then the signal is re-raised with its default
/// action, so the program ends at once as usual but leaves nothing behind.
extern "C" void on_stop_signal(int signal) {
  if (g_stop_signal == 0) {
    g_stop_signal = signal;
    return;
  }
  render::stop_by_signal(signal);
}

/// SIGINT/SIGTERM set a flag that the frame loop reads between frames; a second one ends the
/// program at once (on_stop_signal).
class StopSignals {
 public:
  StopSignals() {
    g_stop_signal = 0;  // before the handler is in, so that no signal is lost
    scope_.emplace(on_stop_signal, std::initializer_list<int>{SIGINT, SIGTERM}, true);
  }
  [[nodiscard]] static int received() { return g_stop_signal; }

 private:
  std::optional<SignalScope> scope_;
};

std::string size_text(const Scene& scene) {
  return std::to_string(scene.render.width) + "x" + std::to_string(scene.render.height);
}

/// "frame 12  t 0.400 s" in the top-left corner, scaled with the image.
void draw_overlay(render::Image& image, int frame, double fps) {
  char text[64];
  std::snprintf(text, sizeof text, "frame %d  t %.3f s", frame, frame / fps);
  render::TextStyle style;
  style.scale = std::max(1, image.height / 180);
  render::draw_text(image, style.scale * 2, style.scale * 2, text, style);
}

/// COLSxROWS for --sheet. @throws SceneError.
std::pair<int, int> parse_grid(const std::string& text) {
  std::string grid = text;
  for (char& c : grid) c = c == 'X' ? 'x' : c;
  const auto cr = parse_pair(grid, 'x', 1, 64);
  if (!cr) throw SceneError("--sheet " + text + ": expected COLSxROWS with each in [1, 64], e.g. 4x4");
  return {int(cr->first), int(cr->second)};
}

bool is_fatal_output(const std::string& output) { return !is_video_path(output); }

}  // namespace

int render_command(const RenderOptions& o) {
  int first = 0;
  const Scene scene = prepare_scene(o, &first);
  const int end = scene.frames;
  std::vector<std::string> outputs = o.outputs;
  if (outputs.empty() && o.contact_sheet.empty() && o.hash_file.empty()) {
    const std::string stem = fs::path(o.scene).stem().string();
    outputs = {"out/" + stem, "out/" + stem + ".mp4"};
  }
  for (const auto& out : outputs) {
    const fs::path p(out);
    if (p.has_extension() && !is_video_path(p) && !fs::is_directory(p))
      throw SceneError("-o " + out + ": expected a directory (PNG frames) or a .mp4, .webm or .gif file");
  }
  for (const auto& out : outputs) {
    if (o.crf > 51 && lower(fs::path(out).extension().string()) == ".mp4")
      throw SceneError("--crf " + std::to_string(o.crf) + ": expected 0..51 for H.264 (" + out + ")");
  }
  if (!o.contact_sheet.empty() && lower(fs::path(o.contact_sheet).extension().string()) != ".png")
    throw SceneError("--contact-sheet " + o.contact_sheet + ": expected a .png file");
  {
    std::vector<OutputPath> checked;
    for (const auto& out : outputs) checked.push_back({"-o", out, !is_video_path(fs::path(out))});
    checked.push_back({"--contact-sheet", o.contact_sheet, false});
    checked.push_back({"--hash", o.hash_file, false});
    check_outputs(checked);
  }
  const auto [sheet_cols, sheet_rows] = parse_grid(o.sheet_grid);
  // (the range `check` reads back from the golden)
  if (o.hash_every < 1 || o.hash_every > 1000000)
    throw SceneError("--hash-every " + std::to_string(o.hash_every) + ": expected an integer in [1, 1000000]");
  if (!o.bitrate.empty() && !render::video_bitrate(o.bitrate))
    throw SceneError("--bitrate " + o.bitrate + ": expected a number with an optional k or M suffix in [1k, 10000M], e.g. 4M");

  // A cache must be the bake of this very scene (file bytes, overrides, seed, fps, build) and
  // hold every frame of the range: checked before anything is written.
  std::uint64_t cache_key = 0;
  if (!o.cache.empty()) {
    const CacheManifest m = read_manifest(o.cache);
    if (const std::string d = identity_difference(m.id, cache_identity(scene, o.scene, o.overrides)); !d.empty())
      throw SceneError(manifest_path(o.cache).string() + ": the cache does not match " + o.scene + ": " + d);
    cache_key = m.id.key();
    if (end > m.frames)
      throw SceneError(manifest_path(o.cache).string() + ": frames " + std::to_string(first) + ".." +
                       std::to_string(end - 1) + " requested, the cache holds frames 0.." +
                       std::to_string(m.frames - 1));
    std::vector<std::string> missing;
    for (int f = first; f < end; ++f)
      if (std::string e = check_frame_header(o.cache, f, cache_key); !e.empty()) missing.push_back(e);
    if (!missing.empty()) throw SceneError(missing);
  }
  std::string cached_state;

  // From here on Ctrl-C stops between frames and closes what was opened.
  const StopSignals stop;
  ScenePlayer player(scene);

  // Outputs that get the frames as shown (overlay included)...
  std::vector<std::unique_ptr<render::FrameSink>> sinks;
  bool has_png = false;
  int exit_code = 0;
  std::vector<std::string> video_paths;
  for (const auto& out : outputs) {
    if (!is_video_path(out)) {
      sinks.push_back(render::make_png_sequence(out, o.png_compression));
      has_png = true;
    } else {
      video_paths.push_back(out);
    }
  }
  render::VideoOptions video{scene.fps, o.crf, o.bitrate,
                             scene.render.background == render::Background::transparent};
  for (const auto& out : video_paths) {
    try {
      sinks.push_back(render::make_video(out, scene.render.width, scene.render.height, video));
    } catch (const render::IoError& e) {
      exit_code = 1;
      if (!has_png) {
        // Never lose the render: fall back to PNG frames beside the requested video. The video's
        // error is printed first, so a failing fallback (same unusable folder) cannot hide it.
        fs::path dir = fs::path(out).replace_extension("");
        dir += "_frames";
        std::cerr << "simreel: " << e.what() << "; writing PNG frames to " << dir.string() << " instead\n";
        sinks.push_back(render::make_png_sequence(dir, o.png_compression));
        has_png = true;
      } else {
        std::cerr << "simreel: " << e.what() << "; the PNG frames are still written\n";
      }
    }
  }
  std::vector<int> sheet_frames;
  if (!o.contact_sheet.empty()) {
    sheet_frames = render::contact_sheet_frames(first, end - first, sheet_cols * sheet_rows);
    render::ContactSheetLayout layout;
    layout.columns = sheet_cols;
    layout.rows = sheet_rows;
    layout.thumb_width = std::clamp(1920 / sheet_cols, 64, 480);
    sinks.push_back(render::make_contact_sheet(o.contact_sheet, scene.render.width, scene.render.height,
                                               sheet_frames, layout));
  }
  const bool every_frame = !outputs.empty();
  // ...and the hash record, which sees the clean frames.
  std::vector<std::unique_ptr<render::FrameSink>> hash_sinks;
  HashRecord record;
  if (!o.hash_file.empty()) {
    record.scene = scene_relative_to_golden(o.scene, o.hash_file);
    record.overrides = o.overrides;
    record.seed = static_cast<long long>(scene.seed);
    record.width = scene.render.width;
    record.height = scene.render.height;
    record.fps = scene.fps;
    record.first = first;
    record.end = end;
    record.every = o.hash_every;
    record.backend = player.context().backend_name();
    record.simreel_version = SIMREEL_VERSION;
    record.gl_renderer = player.context().renderer_string();
    record.gl_version = player.context().version_string();
    hash_sinks.push_back(make_hash_recorder(o.hash_file, record));
  }
  const std::size_t depth = o.sync_writes ? 0 : 4;
  render::FrameWriter writer(std::move(sinks), depth);
  render::FrameWriter hash_writer(std::move(hash_sinks), depth);
  auto wanted = [&](int frame) {
    return every_frame || is_hashed_frame(record, frame) ||
           std::find(sheet_frames.begin(), sheet_frames.end(), frame) != sheet_frames.end();
  };
  auto report_failures = [&] {
    for (const auto& f : writer.take_failures()) {
      if (is_fatal_output(f.output)) throw render::IoError(f.message);
      std::cerr << "\nsimreel: " << f.message << (has_png ? "; the PNG frames are still written\n" : "\n");
      exit_code = 1;
    }
    for (const auto& f : hash_writer.take_failures()) throw render::IoError(f.message);
  };

  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  for (int frame = first; frame < end; ++frame) {
    if (StopSignals::received() != 0) break;
    if (!wanted(frame)) continue;
    // Frame k shows the state at t = k / fps: frame 0 is the initial state.
    if (o.cache.empty()) {
      player.advance_to(frame);
    } else {
      if (std::string e = read_frame(o.cache, frame, cache_key, cached_state); !e.empty()) throw SceneError(e);
      try {
        player.restore(frame, cached_state);
      } catch (const sim::StateError& e) {
        throw SceneError(frame_path(o.cache, frame).string() + ": " + e.what());
      }
    }
    auto image = std::make_shared<render::Image>(player.render());
    if (!o.hash_file.empty()) hash_writer.write(image, frame);
    if (o.overlay) {
      auto shown = std::make_shared<render::Image>(*image);
      draw_overlay(*shown, frame, scene.fps);
      image = std::move(shown);
    }
    writer.write(std::move(image), frame);
    report_failures();
    ++done;
    if (progress) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double fps = (frame + 1 - first) / std::max(elapsed, 1e-9);
      std::fprintf(stderr, "\rframe %d/%d  %.1f fps  ETA %s   ", frame + 1, end, fps,
                   format_duration((end - frame - 1) / fps).c_str());
    }
  }
  if (progress) std::fputc('\n', stderr);
  const int signal = StopSignals::received();
  // Interrupted: the videos and sheet are closed so they play; a hash record of part of the
  // range would be a misleading golden, so it is not written.
  std::vector<std::string> written = writer.finish();
  if (signal == 0) {
    for (auto& w : hash_writer.finish()) written.push_back(w);
  }
  report_failures();
  for (const auto& w : written) std::cout << "wrote " << w << "\n";
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << done << " frames " << size_text(scene) << " in " << format_duration(elapsed) << " with "
            << player.context().backend_name() << ": " << player.context().renderer_string() << ", OpenGL "
            << player.context().version_string() << "\n";
  if (signal != 0) {
    std::cerr << "simreel: interrupted after " << done << " frames; outputs closed"
              << (o.hash_file.empty() ? "" : ", hash record not written") << "\n";
    return 128 + signal;
  }
  return exit_code;
}

}  // namespace simreel::app
