#include "commands.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <charconv>
#include <chrono>
#include <cerrno>
#include <cinttypes>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <utility>

#include "golden.hpp"
#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/render/frame_sink.hpp"
#include "simreel/render/mesh.hpp"
#include "simreel/render/camera_path.hpp"
#include "simreel/render/image_hash.hpp"
#include "simreel/render/text_overlay.hpp"

#ifndef SIMREEL_VERSION
#define SIMREEL_VERSION "unknown"
#endif

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

/// --frames "N" or "A:B" -> [first, end). @throws SceneError.
std::pair<int, int> parse_frames(const std::string& text) {
  int a = 0, b = 0;
  char colon = 0, extra = 0;
  const int n = std::sscanf(text.c_str(), "%d%c%d%c", &a, &colon, &b, &extra);
  if (n == 1 && a >= 1 && text.find_first_not_of("0123456789") == std::string::npos) return {0, a};
  if (n == 3 && colon == ':' && a >= 0 && b > a && text.find_first_not_of("0123456789:") == std::string::npos)
    return {a, b};
  throw SceneError("--frames " + text + ": expected a count N >= 1 or a range A:B with 0 <= A < B");
}

/// Applies the command-line options that override scene values, checking them as usage errors.
/// `first` receives the first frame to output (frames before it are simulated only).
Scene prepare_scene(const RunOptions& o, int* first = nullptr) {
  Scene scene = load_scene(o.scene, o.overrides);
  if (first != nullptr) *first = 0;
  if (o.frames) {
    const auto [a, b] = parse_frames(*o.frames);
    if (first != nullptr) *first = a;
    scene.frames = b;
  }
  if (o.fps) {
    if (!(*o.fps > 0.0 && *o.fps <= 1000.0))
      throw SceneError("--fps " + std::to_string(*o.fps) + ": expected a number in (0, 1000]");
    scene.fps = *o.fps;
  }
  if (o.seed) {
    if (*o.seed < 0) throw SceneError("--seed " + std::to_string(*o.seed) + ": expected an integer >= 0");
    scene.seed = std::uint64_t(*o.seed);
  }
  if (o.size) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(o.size->c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 16 ||
        h < 16 || w > 8192 || h > 8192)
      throw SceneError("--size " + *o.size + ": expected WIDTHxHEIGHT with each in [16, 8192], e.g. 1280x720");
    scene.render.width = w;
    scene.render.height = h;
  }
  if (o.backend) {
    try {
      scene.backend = render::parse_backend(*o.backend);
    } catch (const std::invalid_argument&) {
      throw SceneError("--backend " + *o.backend + ": expected osmesa or egl");
    }
  }
  return scene;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool is_video_path(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".mp4" || ext == ".gif" || ext == ".webm";
}

/// Renderer material of a collider drawn in its scene colour.
render::Material collider_material(const ColliderScene& c) {
  render::Material m;
  m.base_color = c.color;
  m.checker_m = c.checker_m;
  return m;
}

/// The imported file as the renderer's mesh, scaled to the collider's local frame; the first
/// material's colour unless the scene gives one (ColliderScene::color is the scene's choice).
render::MeshDesc mesh_desc(const ColliderScene& c) {
  render::MeshDesc d;
  const assets::TriangleMesh& m = *c.mesh_asset;
  d.positions.reserve(3 * m.positions.size());
  d.normals.reserve(3 * m.normals.size());
  for (const auto& p : m.positions)
    for (int k = 0; k < 3; ++k) d.positions.push_back(p[k] * float(c.mesh_scale[std::size_t(k)]));
  // Non-uniform scale: normals transform by the inverse scale (then renormalise).
  for (const auto& n0 : m.normals) {
    Eigen::Vector3f n(n0.x() / float(c.mesh_scale[0]), n0.y() / float(c.mesh_scale[1]),
                      n0.z() / float(c.mesh_scale[2]));
    n.normalize();
    d.normals.insert(d.normals.end(), {n.x(), n.y(), n.z()});
  }
  for (const auto& uv : m.uvs) d.uvs.insert(d.uvs.end(), {uv.x(), uv.y()});
  for (const auto& t : m.triangles) d.indices.insert(d.indices.end(), t.begin(), t.end());
  d.material = collider_material(c);
  if (!m.materials.empty() && !m.materials[0].texture.empty() && m.materials[0].texture.string()[0] != '*')
    d.material.texture_path = m.materials[0].texture.string();
  // Open meshes (a ramp's underside, stairs seen from behind) show their inside faces too.
  d.material.double_sided = true;
  return d;
}

void add_scene_drawables(const Scene& scene, const SceneWorld& sw, render::Renderer& r) {
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    const ColliderScene& c = scene.colliders[i];
    const std::uint64_t key = sw.colliders[i].id.packed();
    switch (c.type) {
      case ColliderScene::Type::plane: {
        render::PlaneDesc d;
        d.point = c.plane.point.cast<float>();
        d.normal = c.plane.normal.normalized().cast<float>();
        d.half_size = c.draw_half_size;
        d.color = c.color;
        d.checker_m = c.checker_m;
        r.add_plane(key, d);
        continue;  // a plane's drawable is already in the world frame
      }
      case ColliderScene::Type::box: {
        render::BoxDesc d;
        d.half_extents = c.box.half_extents.cast<float>();
        d.color = c.color;
        r.add_box(key, d);
        break;
      }
      case ColliderScene::Type::sphere: {
        render::MeshDesc d = render::make_sphere_mesh(float(c.sphere.radius), 48);
        d.material = collider_material(c);
        r.add_mesh(key, d);
        break;
      }
      case ColliderScene::Type::cylinder: {
        render::MeshDesc d =
            render::make_cylinder_mesh(float(c.cylinder.radius), float(c.cylinder.half_height), 48);
        d.material = collider_material(c);
        r.add_mesh(key, d);
        break;
      }
      case ColliderScene::Type::mesh:
        r.add_mesh(key, mesh_desc(c));
        break;
    }
    const sim::MovedObject pose = sw.world.pose(sw.colliders[i]);
    r.set_transform(key, pose.translation.cast<float>(), pose.rotation.cast<float>());
  }
  // Cloths: dynamic two-sided meshes in the world frame, vertices replaced every frame.
  for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
    const sim::ClothView v = sw.world.cloth(sw.cloths[i]);
    render::MeshDesc d;
    d.positions.assign(v.positions, v.positions + 3 * v.vertex_count);
    d.normals.assign(v.normals, v.normals + 3 * v.vertex_count);
    // UVs in metres, so checker_m is a cell size on the cloth.
    const sim::ClothDef& def = scene.cloths[i].def;
    d.uvs.resize(2 * v.vertex_count);
    for (std::size_t k = 0; k < v.vertex_count; ++k) {
      d.uvs[2 * k] = v.uvs[2 * k] * float(def.width);
      d.uvs[2 * k + 1] = v.uvs[2 * k + 1] * float(def.height);
    }
    d.indices.assign(v.triangles, v.triangles + 3 * v.triangle_count);
    d.material.base_color = scene.cloths[i].color;
    d.material.checker_m = scene.cloths[i].checker_m;
    d.material.double_sided = true;
    d.material.specular = 0.08f;
    d.dynamic = true;
    r.add_mesh(sw.cloths[i].id.packed(), d);
  }
}

void upload_particles(const Scene& scene, const SceneWorld& sw, render::Renderer& r) {
  for (std::size_t i = 0; i < sw.systems.size(); ++i) {
    const sim::ParticleView v = sw.world.particles(sw.systems[i]);
    render::ParticleBatch b;
    b.count = v.count;
    b.position = v.position;
    b.velocity = v.velocity;
    b.color = v.color;
    b.radius = v.radius;
    b.style = scene.emitters[i].style;
    b.streak_s = scene.emitters[i].streak_s;
    r.set_particles(sw.systems[i].id.packed(), b);
  }
}

void upload_cloths(const SceneWorld& sw, render::Renderer& r) {
  for (const sim::ClothHandle& h : sw.cloths) {
    const sim::ClothView v = sw.world.cloth(h);
    r.update_mesh(h.id.packed(), {v.positions, 3 * v.vertex_count}, {v.normals, 3 * v.vertex_count});
  }
}

std::string format_duration(double s) {
  char buf[32];
  if (s >= 3600) std::snprintf(buf, sizeof buf, "%dh%02dm", int(s / 3600), int(s / 60) % 60);
  else if (s >= 60) std::snprintf(buf, sizeof buf, "%dm%02ds", int(s / 60), int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%.1fs", s);
  return buf;
}

}  // namespace

namespace {

/// The simulation and the renderer of one scene, stepped frame by frame in order.
class ScenePlayer {
 public:
  explicit ScenePlayer(const Scene& scene)
      : scene_(scene),
        sw_(build_world(scene)),
        context_(render::create_context(scene.backend)),
        renderer_(*context_, scene.render) {
    renderer_.set_camera(scene.camera);
    renderer_.set_light(scene.light);
    add_scene_drawables(scene_, sw_, renderer_);
  }

  /// Steps the simulation until it shows frame `frame` (t = frame / fps); frame 0 is the
  /// initial state. Moved colliders reach the renderer at every step, drawn or not.
  void advance_to(int frame) {
    const double dt = 1.0 / scene_.fps;
    for (; frame_ < frame; ++frame_) {
      for (const sim::MovedObject& m : sw_.world.advance(dt))
        renderer_.set_transform(m.handle.packed(), m.translation.cast<float>(), m.rotation.cast<float>());
    }
  }

  render::Image render() {
    upload_particles(scene_, sw_, renderer_);
    upload_cloths(sw_, renderer_);
    renderer_.set_camera(render::camera_at(scene_.camera_motion, double(frame_) / scene_.fps));
    return renderer_.render();
  }

  [[nodiscard]] const render::Context& context() const { return *context_; }

 private:
  const Scene& scene_;
  SceneWorld sw_;
  std::unique_ptr<render::Context> context_;
  render::Renderer renderer_;
  int frame_ = 0;
};

volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void on_stop_signal(int signal) { g_stop_signal = signal; }

/// SIGINT/SIGTERM set a flag that the frame loop reads between frames; the handler is one-shot
/// (SA_RESETHAND), so a second Ctrl-C kills the program at once as usual.
class StopSignals {
 public:
  StopSignals() {
    g_stop_signal = 0;
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND | SA_RESTART;
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  [[nodiscard]] static int received() { return g_stop_signal; }

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
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
  int c = 0, r = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &c, &x, &r, &extra) != 3 || (x != 'x' && x != 'X') || c < 1 || r < 1 ||
      c > 64 || r > 64)
    throw SceneError("--sheet " + text + ": expected COLSxROWS with each in [1, 64], e.g. 4x4");
  return {c, r};
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
  const auto [sheet_cols, sheet_rows] = parse_grid(o.sheet_grid);
  if (o.hash_every < 1) throw SceneError("--hash-every " + std::to_string(o.hash_every) + ": expected an integer >= 1");
  if (!o.bitrate.empty() && o.bitrate.find_first_not_of("0123456789.kKM") != std::string::npos)
    throw SceneError("--bitrate " + o.bitrate + ": expected a number with an optional k or M suffix, e.g. 4M");

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
  render::VideoOptions video{scene.fps, o.crf, o.bitrate};
  for (const auto& out : video_paths) {
    try {
      sinks.push_back(render::make_video(out, scene.render.width, scene.render.height, video));
    } catch (const render::IoError& e) {
      exit_code = 1;
      if (!has_png) {
        // Never lose the render: fall back to PNG frames beside the requested video.
        fs::path dir = fs::path(out).replace_extension("");
        dir += "_frames";
        sinks.push_back(render::make_png_sequence(dir, o.png_compression));
        has_png = true;
        std::cerr << "simreel: " << e.what() << "; writing PNG frames to " << dir.string() << " instead\n";
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
    record.scene = o.scene;
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
    player.advance_to(frame);
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

}  // namespace

int check_command(const CheckOptions& o) {
  const fs::path golden_path(o.golden);
  HashRecord golden = read_hash_record(golden_path);
  if (o.tolerance) golden.tolerance = {*o.tolerance, *o.tolerance, *o.tolerance};
  RunOptions run;
  run.scene = golden.scene;
  run.overrides = golden.overrides;
  run.frames = std::to_string(golden.first) + ":" + std::to_string(golden.end);
  run.fps = golden.fps;
  run.size = std::to_string(golden.width) + "x" + std::to_string(golden.height);
  run.seed = golden.seed;
  run.backend = o.backend ? *o.backend : golden.backend;
  int first = 0;
  const Scene scene = prepare_scene(run, &first);
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

int simulate_command(const RunOptions& o, const std::string& export_csv) {
  int first = 0;
  const Scene scene = prepare_scene(o, &first);
  SceneWorld sw = build_world(scene);
  const fs::path target(export_csv);
  if (target.has_parent_path()) fs::create_directories(target.parent_path());
  std::string tmp_name = target.filename().string();
  tmp_name.insert(tmp_name.begin(), '.');  // hidden, so a partial export never looks finished
  tmp_name.append(".tmp-").append(std::to_string(getpid()));
  const fs::path tmp = target.parent_path() / tmp_name;
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw render::IoError("cannot write " + export_csv + ": " + std::strerror(errno));
  std::string buf;
  buf.reserve(1 << 20);
  buf += "frame,time,system,id,x,y,z,vx,vy,vz\n";
  auto put_float = [&buf](double v) {
    char tmpbuf[32];
    auto res = std::to_chars(tmpbuf, tmpbuf + sizeof tmpbuf, v);
    buf.append(tmpbuf, res.ptr);
  };
  bool ok = true;
  const double dt = 1.0 / scene.fps;
  for (int frame = 0; frame < scene.frames && ok; ++frame) {
    if (frame > 0) sw.world.advance(dt);
    if (frame < first) continue;
    const std::string prefix = std::to_string(frame) + ",";
    // One row per particle, then per cloth vertex (system = cloth name, id = row * columns +
    // column).
    auto rows = [&](const std::string& name, std::size_t n, const float* x, const float* v,
                    const std::uint64_t* ids) {
      for (std::size_t p = 0; p < n; ++p) {
        buf += prefix;
        put_float(sw.world.time());
        buf += ',';
        buf += name;
        buf += ',';
        buf += std::to_string(ids ? ids[p] : p);
        for (std::size_t k = 0; k < 3; ++k) {
          buf += ',';
          put_float(x[3 * p + k]);
        }
        for (std::size_t k = 0; k < 3; ++k) {
          buf += ',';
          put_float(v[3 * p + k]);
        }
        buf += '\n';
      }
      if (buf.size() > (1u << 20)) {
        ok = std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
        buf.clear();
      }
    };
    for (std::size_t i = 0; i < sw.systems.size(); ++i) {
      const sim::ParticleView v = sw.world.particles(sw.systems[i]);
      rows(scene.emitters[i].system.name, v.count, v.position, v.velocity, v.id);
    }
    for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
      const sim::ClothView v = sw.world.cloth(sw.cloths[i]);
      rows(scene.cloths[i].def.name, v.vertex_count, v.positions, v.velocities, nullptr);
    }
  }
  ok = ok && std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) {
    fs::remove(tmp);
    throw render::IoError("cannot write " + export_csv + ": write failed (disk full?)");
  }
  fs::rename(tmp, target);
  std::cout << "wrote " << export_csv << " (" << scene.frames - first << " frames, t = " << sw.world.time() << " s)\n";
  return 0;
}

int validate_command(const std::string& scene_path, const std::vector<std::string>& overrides) {
  const Scene scene = load_scene(scene_path, overrides);
  (void)build_world(scene);
  std::cout << "ok\n";
  return 0;
}

int hash_command(const std::vector<std::string>& images, const std::string& algorithm) {
  int code = 0;
  for (const auto& path : images) {
    try {
      const render::Image img = render::read_image(path);
      if (algorithm == "all") {
        const FrameHashes h = hash_frame(img, 0);
        std::cout << "phash " << render::hash_to_hex(h.phash) << "  dhash " << render::hash_to_hex(h.dhash)
                  << "  chash " << render::hash_to_hex(h.chash) << "  " << path << "\n";
        continue;
      }
      const std::uint64_t h = algorithm == "dhash"   ? render::dhash(img)
                              : algorithm == "chash" ? render::chash(img)
                                                     : render::phash(img);
      std::cout << render::hash_to_hex(h) << "  " << path << "\n";
    } catch (const render::IoError& e) {
      std::cerr << "simreel: " << e.what() << "\n";
      code = 2;
    }
  }
  return code;
}

}  // namespace simreel::app
