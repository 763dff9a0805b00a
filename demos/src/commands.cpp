#include "commands.hpp"

#include <algorithm>
#include <unistd.h>

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

#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/render/frame_sink.hpp"
#include "simreel/render/image_hash.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

/// Applies the command-line options that override scene values, checking them as usage errors.
Scene prepare_scene(const RunOptions& o) {
  Scene scene = load_scene(o.scene, o.overrides);
  if (o.frames) {
    if (*o.frames < 1) throw SceneError("--frames " + std::to_string(*o.frames) + ": expected an integer >= 1");
    scene.frames = *o.frames;
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

bool is_video_path(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext == ".mp4" || ext == ".gif";
}

void add_scene_drawables(const Scene& scene, const SceneWorld& sw, render::Renderer& r) {
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    const ColliderScene& c = scene.colliders[i];
    const std::uint64_t key = sw.colliders[i].id.packed();
    if (c.type == ColliderScene::Type::plane) {
      render::PlaneDesc d;
      d.point = c.plane.point.cast<float>();
      d.normal = c.plane.normal.normalized().cast<float>();
      d.half_size = c.draw_half_size;
      d.color = c.color;
      d.checker_m = c.checker_m;
      r.add_plane(key, d);
    } else if (c.type != ColliderScene::Type::box) {
      // TODO(renderer mesh API): draw spheres, cylinders and meshes (c.mesh_asset, scaled by
      // c.mesh_scale, colour c.color) under `key`, with the pose below; the moved list updates
      // it. Until then they are simulated but not drawn, and set_transform skips their keys.
      continue;
    } else {
      render::BoxDesc d;
      d.half_extents = c.box.half_extents.cast<float>();
      d.color = c.color;
      r.add_box(key, d);
      const sim::MovedObject pose = sw.world.pose(sw.colliders[i]);
      r.set_transform(key, pose.translation.cast<float>(), pose.rotation.cast<float>());
    }
  }
}

void upload_particles(const Scene& scene, const SceneWorld& sw, render::Renderer& r) {
  for (std::size_t i = 0; i < sw.systems.size(); ++i) {
    const sim::ParticleView v = sw.world.particles(sw.systems[i]);
    render::ParticleBatch b;
    b.count = v.count;
    b.position = v.position;
    b.color = v.color;
    b.radius = v.radius;
    b.style = scene.emitters[i].style;
    b.velocity = v.velocity;  // streaks stretch along it
    b.streak_s = scene.emitters[i].streak_s;
    r.set_particles(sw.systems[i].id.packed(), b);
  }
}

// --- Cloth drawing hook (issue 6) -----------------------------------------------------------
// The renderer's triangle-mesh API (add_mesh / update_mesh) is written in parallel. Until it is
// merged, each cloth is drawn as small sprites at its vertices so cloth scenes can be looked at.
// At merge: replace the body with one update_mesh(key, view.positions, view.normals) per cloth
// (triangles and UVs from the view are fixed for the cloth's life; upload them once).
struct ClothSprites {
  std::vector<float> color, radius;
};

void upload_cloths(const Scene& scene, const SceneWorld& sw, render::Renderer& r,
                   std::vector<ClothSprites>& sprites) {
  sprites.resize(sw.cloths.size());
  for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
    const sim::ClothView v = sw.world.cloth(sw.cloths[i]);
    const sim::ClothDef& d = scene.cloths[i].def;
    ClothSprites& s = sprites[i];
    if (s.radius.size() != v.vertex_count) {
      const double spacing = std::min(d.columns > 1 ? d.width / double(d.columns - 1) : d.height,
                                      d.rows > 1 ? d.height / double(d.rows - 1) : d.width);
      s.radius.assign(v.vertex_count, float(0.6 * spacing));
      s.color.resize(4 * v.vertex_count);
      const render::Vec4f c = scene.cloths[i].color;
      for (std::size_t k = 0; k < v.vertex_count; ++k) {
        // Shade by the checker on the UVs so folds read in the sprites.
        float shade = 1.f;
        if (scene.cloths[i].checker_m > 0.f) {
          const auto cu = int(std::floor(v.uvs[2 * k] * d.width / scene.cloths[i].checker_m));
          const auto cv = int(std::floor(v.uvs[2 * k + 1] * d.height / scene.cloths[i].checker_m));
          shade = ((cu + cv) & 1) ? 0.6f : 1.f;
        }
        for (int ch = 0; ch < 3; ++ch) s.color[4 * k + std::size_t(ch)] = c[ch] * shade;
        s.color[4 * k + 3] = 1.f;
      }
    }
    render::ParticleBatch b;
    b.count = v.vertex_count;
    b.position = v.positions;
    b.color = s.color.data();
    b.radius = s.radius.data();
    r.set_particles(sw.cloths[i].id.packed(), b);
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

int render_command(const RenderOptions& o) {
  const Scene scene = prepare_scene(o);
  std::vector<std::string> outputs = o.outputs;
  if (outputs.empty()) {
    const std::string stem = fs::path(o.scene).stem().string();
    outputs = {"out/" + stem, "out/" + stem + ".mp4"};
  }
  for (const auto& out : outputs) {
    const fs::path p(out);
    if (p.has_extension() && !is_video_path(p) && !fs::is_directory(p))
      throw SceneError("-o " + out + ": expected a directory (PNG frames) or a .mp4 or .gif file");
  }

  SceneWorld sw = build_world(scene);
  std::unique_ptr<render::Context> context = render::create_context(scene.backend);
  render::Renderer renderer(*context, scene.render);
  renderer.set_camera(scene.camera);
  renderer.set_light(scene.light);
  add_scene_drawables(scene, sw, renderer);

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
  for (const auto& out : video_paths) {
    try {
      sinks.push_back(render::make_video(out, scene.render.width, scene.render.height,
                                         render::VideoOptions{scene.fps, o.crf}));
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

  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  const double dt = 1.0 / scene.fps;
  std::vector<ClothSprites> cloth_sprites;
  const auto start = std::chrono::steady_clock::now();
  for (int frame = 0; frame < scene.frames; ++frame) {
    // Frame k shows the state at t = k / fps: frame 0 is the initial state.
    if (frame > 0) {
      for (const sim::MovedObject& m : sw.world.advance(dt)) {
        // TODO(renderer mesh API): remove this check once every collider type is drawn.
        const auto drawn = std::find_if(sw.colliders.begin(), sw.colliders.end(),
                                        [&](const sim::ColliderHandle& h) { return h.id == m.handle; });
        if (drawn == sw.colliders.end() ||
            scene.colliders[std::size_t(drawn - sw.colliders.begin())].type == ColliderScene::Type::plane ||
            scene.colliders[std::size_t(drawn - sw.colliders.begin())].type == ColliderScene::Type::box)
          renderer.set_transform(m.handle.packed(), m.translation.cast<float>(), m.rotation.cast<float>());
      }
    }
    upload_particles(scene, sw, renderer);
    upload_cloths(scene, sw, renderer, cloth_sprites);
    renderer.set_camera(render::camera_at(scene.camera_motion, frame * dt));  // camera.path / orbit
    const render::Image image = renderer.render();
    for (std::size_t s = 0; s < sinks.size();) {
      try {
        sinks[s]->write(image, frame);
        ++s;
      } catch (const render::IoError& e) {
        if (!is_video_path(sinks[s]->describe())) throw;  // a PNG that cannot be written is fatal
        std::cerr << "\nsimreel: " << e.what() << "; the PNG frames are still written\n";
        sinks[s]->abort();
        sinks.erase(sinks.begin() + std::ptrdiff_t(s));
        exit_code = 1;
      }
    }
    if (progress) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double fps = (frame + 1) / std::max(elapsed, 1e-9);
      std::fprintf(stderr, "\rframe %d/%d  %.1f fps  ETA %s   ", frame + 1, scene.frames, fps,
                   format_duration((scene.frames - frame - 1) / fps).c_str());
    }
  }
  if (progress) std::fputc('\n', stderr);
  for (auto& sink : sinks) {
    try {
      sink->finish();
      std::cout << "wrote " << sink->describe() << "\n";
    } catch (const render::IoError& e) {
      if (!is_video_path(sink->describe())) throw;
      std::cerr << "simreel: " << e.what() << "; the PNG frames are still written\n";
      exit_code = 1;
    }
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << scene.frames << " frames " << scene.render.width << "x" << scene.render.height << " in "
            << format_duration(elapsed) << " with " << context->backend_name() << ": "
            << context->renderer_string() << ", OpenGL " << context->version_string() << "\n";
  return exit_code;
}

int simulate_command(const RunOptions& o, const std::string& export_csv) {
  const Scene scene = prepare_scene(o);
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
    const std::string prefix = std::to_string(frame) + ",";
    for (std::size_t i = 0; i < sw.systems.size(); ++i) {
      const sim::ParticleView v = sw.world.particles(sw.systems[i]);
      const std::string& name = scene.emitters[i].system.name;
      for (std::size_t p = 0; p < v.count; ++p) {
        buf += prefix;
        put_float(sw.world.time());
        buf += ',';
        buf += name;
        buf += ',';
        buf += std::to_string(v.id[p]);
        for (int k = 0; k < 3; ++k) {
          buf += ',';
          put_float(v.position[3 * p + k]);
        }
        for (int k = 0; k < 3; ++k) {
          buf += ',';
          put_float(v.velocity[3 * p + k]);
        }
        buf += '\n';
      }
      if (buf.size() > (1u << 20)) {
        ok = std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
        buf.clear();
      }
    }
    // Cloth vertices: system = cloth name, id = vertex index (row * columns + column).
    for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
      const sim::ClothView v = sw.world.cloth(sw.cloths[i]);
      const std::string& name = scene.cloths[i].def.name;
      for (std::size_t p = 0; p < v.vertex_count; ++p) {
        buf += prefix;
        put_float(sw.world.time());
        buf += ',';
        buf += name;
        buf += ',';
        buf += std::to_string(p);
        for (int k = 0; k < 3; ++k) {
          buf += ',';
          put_float(v.positions[3 * p + std::size_t(k)]);
        }
        for (int k = 0; k < 3; ++k) {
          buf += ',';
          put_float(v.velocities[3 * p + std::size_t(k)]);
        }
        buf += '\n';
      }
      if (buf.size() > (1u << 20)) {
        ok = std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
        buf.clear();
      }
    }
  }
  ok = ok && std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) {
    fs::remove(tmp);
    throw render::IoError("cannot write " + export_csv + ": write failed (disk full?)");
  }
  fs::rename(tmp, target);
  std::cout << "wrote " << export_csv << " (" << scene.frames << " frames, t = " << sw.world.time() << " s)\n";
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
      const std::uint64_t h = algorithm == "dhash" ? render::dhash(img) : render::phash(img);
      std::cout << render::hash_to_hex(h) << "  " << path << "\n";
    } catch (const render::IoError& e) {
      std::cerr << "simreel: " << e.what() << "\n";
      code = 2;
    }
  }
  return code;
}

}  // namespace simreel::app
