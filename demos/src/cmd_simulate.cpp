// `simreel simulate`: run a scene without rendering and export particle and cloth state, body
// poses and joint readings as CSV.
#include <charconv>
#include <iostream>
#include <memory>
#include <utility>
#include <vector>
#include <string>

#include "commands.hpp"
#include "run_options.hpp"
#include "simreel/render/atomic_file.hpp"

namespace simreel::app {

int simulate_command(const RunOptions& o, const SimulateExports& exports) {
  if (exports.particles.empty() && exports.bodies.empty() && exports.joints.empty())
    throw SceneError("simulate: expected at least one of --export, --export-bodies, --export-joints, found none");
  check_outputs({{"--export", exports.particles, false},
                 {"--export-bodies", exports.bodies, false},
                 {"--export-joints", exports.joints, false}});
  int first = 0;
  const Scene scene = prepare_scene(o, &first);
  SceneWorld sw = build_world(scene);
  // Each CSV is written to a hidden temporary and renamed when complete, so a partial export
  // never looks finished (render::AtomicFile).
  struct Output {
    std::unique_ptr<render::AtomicFile> file;
    std::string buf;
    void flush(bool force) {
      if (file && (force || buf.size() > (1u << 20))) {
        file->write(buf);
        buf.clear();
      }
    }
  };
  Output particles, bodies, joints;
  auto open = [](Output& out, const std::string& path, const char* header) {
    if (path.empty()) return;
    out.file = std::make_unique<render::AtomicFile>(path);
    out.buf.reserve(1 << 20);
    out.buf += header;
  };
  // A Ctrl-C or SIGTERM from here on removes the temporaries: main() installed that handler
  // (render::remove_temporaries_on_signals) before any command ran.
  open(particles, exports.particles, "frame,time,system,id,x,y,z,vx,vy,vz\n");
  open(bodies, exports.bodies, "frame,time,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n");
  open(joints, exports.joints, "frame,time,joint,anchor_error,fx,fy,fz,force,angle,twist,broken\n");
  auto put_float = [](std::string& buf, double v) {
    char tmpbuf[32];
    auto res = std::to_chars(tmpbuf, tmpbuf + sizeof tmpbuf, v);
    buf.append(tmpbuf, res.ptr);
  };
  auto put_vec = [&](std::string& buf, const sim::Vec3& v) {
    for (int k = 0; k < 3; ++k) {
      buf += ',';
      put_float(buf, v[k]);
    }
  };
  // The dynamic bodies (scene order: colliders, chain links, ragdoll segments).
  std::vector<std::size_t> dynamic;
  for (std::size_t i = 0; i < scene.colliders.size(); ++i)
    if (scene.colliders[i].dynamic.enabled) dynamic.push_back(i);
  const double dt = 1.0 / scene.fps;
  for (int frame = 0; frame < scene.frames; ++frame) {
    if (frame > 0) sw.world.advance(dt);
    if (frame < first) continue;
    std::string prefix = std::to_string(frame) + ",";
    {
      std::string t;
      put_float(t, sw.world.time());
      prefix += t + ",";
    }
    // One row per particle, then per cloth vertex (system = cloth name, id = row * columns +
    // column).
    auto rows = [&](const std::string& name, std::size_t n, const float* x, const float* v,
                    const std::uint64_t* ids) {
      std::string& buf = particles.buf;
      for (std::size_t p = 0; p < n; ++p) {
        buf += prefix;
        buf += name;
        buf += ',';
        buf += std::to_string(ids ? ids[p] : p);
        for (std::size_t k = 0; k < 3; ++k) {
          buf += ',';
          put_float(buf, x[3 * p + k]);
        }
        for (std::size_t k = 0; k < 3; ++k) {
          buf += ',';
          put_float(buf, v[3 * p + k]);
        }
        buf += '\n';
      }
      particles.flush(false);
    };
    if (particles.file) {
      for (std::size_t i = 0; i < sw.systems.size(); ++i) {
        const sim::ParticleView v = sw.world.particles(sw.systems[i]);
        rows(scene.emitters[i].system.name, v.count, v.position, v.velocity, v.id);
      }
      for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
        const sim::ClothView v = sw.world.cloth(sw.cloths[i]);
        rows(scene.cloths[i].def.name, v.vertex_count, v.positions, v.velocities, nullptr);
      }
    }
    // Bodies: the pose of the body frame (the shape's centre for one-shape bodies; World::pose),
    // its rotation as a unit quaternion (w, x, y, z) and the frame's velocities (World::velocity).
    if (bodies.file) {
      for (const std::size_t i : dynamic) {
        const sim::MovedObject pose = sw.world.pose(sw.colliders[i]);
        const auto [v, w] = sw.world.velocity(sw.colliders[i]);
        const sim::Quat q(pose.rotation);
        std::string& buf = bodies.buf;
        buf += prefix;
        buf += scene.colliders[i].name;
        put_vec(buf, pose.translation);
        for (const double c : {q.w(), q.x(), q.y(), q.z()}) {
          buf += ',';
          put_float(buf, c);
        }
        put_vec(buf, v);
        put_vec(buf, w);
        buf += '\n';
      }
      bodies.flush(false);
    }
    // Joints: World::joint_state (joint.hpp): drift (m), force on body b (N), angle/twist (rad).
    if (joints.file) {
      for (std::size_t i = 0; i < sw.joints.size(); ++i) {
        const sim::JointReading s = sw.world.joint_state(sw.joints[i]);
        std::string& buf = joints.buf;
        buf += prefix;
        buf += scene.joints[i].def.name;
        buf += ',';
        put_float(buf, s.anchor_error);
        put_vec(buf, s.force);
        buf += ',';
        put_float(buf, s.force.norm());
        buf += ',';
        put_float(buf, s.angle);
        buf += ',';
        put_float(buf, s.twist);
        buf += s.broken ? ",1\n" : ",0\n";
      }
      joints.flush(false);
    }
  }
  const int frames = scene.frames - first;
  for (auto [out, path] : {std::pair{&particles, &exports.particles}, std::pair{&bodies, &exports.bodies},
                           std::pair{&joints, &exports.joints}}) {
    if (!out->file) continue;
    out->flush(true);
    out->file->commit();
    std::cout << "wrote " << *path << " (" << frames << " frames, t = " << sw.world.time() << " s)\n";
  }
  return 0;
}

}  // namespace simreel::app
