// `simreel simulate`: run a scene without rendering and export particle and cloth state as CSV.
#include <charconv>
#include <csignal>
#include <iostream>
#include <string>

#include "commands.hpp"
#include "run_options.hpp"
#include "simreel/render/atomic_file.hpp"

namespace simreel::app {

namespace {

/// Ctrl-C or SIGTERM during an export: remove the CSV's temporary (async-signal-safe), then end
/// by the signal as usual.
extern "C" void on_simulate_signal(int signal) {
  render::remove_temporaries_now();
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

}  // namespace

int simulate_command(const RunOptions& o, const std::string& export_csv) {
  int first = 0;
  const Scene scene = prepare_scene(o, &first);
  SceneWorld sw = build_world(scene);
  // Written to a hidden temporary and renamed when complete, so a partial export never looks
  // finished (render::AtomicFile).
  render::AtomicFile file(export_csv);
  std::signal(SIGINT, on_simulate_signal);
  std::signal(SIGTERM, on_simulate_signal);
  std::string buf;
  buf.reserve(1 << 20);
  buf += "frame,time,system,id,x,y,z,vx,vy,vz\n";
  auto put_float = [&buf](double v) {
    char tmpbuf[32];
    auto res = std::to_chars(tmpbuf, tmpbuf + sizeof tmpbuf, v);
    buf.append(tmpbuf, res.ptr);
  };
  const double dt = 1.0 / scene.fps;
  for (int frame = 0; frame < scene.frames; ++frame) {
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
        file.write(buf);
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
  file.write(buf);
  file.commit();
  std::cout << "wrote " << export_csv << " (" << scene.frames - first << " frames, t = " << sw.world.time() << " s)\n";
  return 0;
}

}  // namespace simreel::app
