// `simreel bake`: simulate a scene once and write its engine state per frame into a cache folder
// (sim_cache.hpp, docs/cache.md), optionally with PLY files of its particles and cloth; with
// --resume, continue a killed bake from its last complete frame.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "json_reader.hpp"
#include "ply_export.hpp"
#include "run_options.hpp"
#include "sim_cache.hpp"
#include "simreel/render/atomic_file.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

/// The first frame not (validly) in the cache, scanning headers from frame 0; the last one
/// before it is read in full (checksum) into `state`, going back while it fails.
int resume_point(const fs::path& dir, int frames, std::uint64_t key, std::string& state) {
  int k = 0;
  while (k < frames && check_frame_header(dir, k, key).empty()) ++k;
  while (k > 0) {
    const std::string e = read_frame(dir, k - 1, key, state);
    if (e.empty()) break;
    std::cerr << "simreel: " << e << "; baking it again\n";
    --k;
  }
  return k;
}

}  // namespace

int bake_command(const BakeOptions& o) {
  int first = 0;
  const Scene scene = prepare_scene(o, &first);
  if (first != 0)
    throw SceneError("--frames " + *o.frames + ": bake takes a frame count N (frames 0..N-1), not a range");
  if (o.cache.empty()) throw SceneError("--cache: expected a folder");
  const int frames = scene.frames;
  const fs::path dir = o.cache;
  if (fs::exists(dir) && !fs::is_directory(dir))
    throw SceneError("--cache " + o.cache + ": is a file, expected a folder");
  check_outputs({{"--cache", o.cache, true}});  // (a folder above it that is a file)

  CacheManifest manifest;
  manifest.id = cache_identity(scene, o.scene, o.overrides);
  manifest.scene = o.scene;
  manifest.frames = frames;
  manifest.ply = o.ply;
  const std::uint64_t key = manifest.id.key();

  SceneWorld sw = build_world(scene);
  std::string state, scratch, ply;
  int start = 0;
  if (o.resume && fs::exists(manifest_path(dir))) {
    const CacheManifest old = read_manifest(dir);
    if (const std::string d = identity_difference(old.id, manifest.id); !d.empty())
      throw SceneError(manifest_path(dir).string() + ": cannot resume: " + d +
                       " (bake without --resume to start over, or into another folder)");
    if (old.ply != o.ply)
      throw SceneError(manifest_path(dir).string() + ": cannot resume: the cache was baked " +
                       (old.ply ? "with" : "without") + " --ply");
    remove_stale_temporaries(dir);
    start = resume_point(dir, frames, key, state);
    if (start > 0) {
      try {
        sw.world.load_state(state);
      } catch (const sim::StateError& e) {
        throw SceneError(frame_path(dir, start - 1).string() + ": " + e.what());
      }
    }
  }
  write_manifest(dir, manifest);

  const double dt = 1.0 / scene.fps;
  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  double write_s = 0.0;
  std::uint64_t state_bytes = 0, ply_bytes = 0;
  auto write = [&](int frame) {
    const auto w0 = clock::now();
    if (o.ply) {
      for (std::size_t i = 0; i < sw.systems.size(); ++i) {
        particles_ply(sw.world.particles(sw.systems[i]), ply);
        render::write_file_atomic(ply_file(dir, "system", int(i), frame), ply);
        ply_bytes += ply.size();
      }
      for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
        const ClothScene& c = scene.cloths[i];
        const float rgba[4] = {c.color[0], c.color[1], c.color[2], c.color[3]};
        cloth_ply(sw.world.cloth(sw.cloths[i]), rgba, float(0.5 * c.def.thickness), ply);
        render::write_file_atomic(ply_file(dir, "cloth", int(i), frame), ply);
        ply_bytes += ply.size();
      }
    }
    // The state last: a frame counts as baked once its state file exists, so its PLY files are
    // complete whenever it is.
    sw.world.save_state(state);
    write_frame(dir, frame, key, state, scratch);
    state_bytes += scratch.size();
    write_s += std::chrono::duration<double>(clock::now() - w0).count();
    if (progress) std::fprintf(stderr, "\rbaked frame %d/%d   ", frame + 1, frames);
  };
  int frame = start;
  if (frame == 0 && frames > 0) write(frame++);
  for (; frame < frames; ++frame) {
    sw.world.advance(dt);
    write(frame);
  }
  if (progress) std::fputc('\n', stderr);
  manifest.complete = true;
  write_manifest(dir, manifest);

  const double total = std::chrono::duration<double>(clock::now() - t0).count();
  const int baked = frames - start;
  std::cout << "baked frames " << start << ".." << frames - 1 << " of " << scene.file << " into " << dir.string();
  if (start > 0) std::cout << " (resumed after frame " << start - 1 << ")";
  std::cout << "\n";
  if (baked > 0) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "%d frames in %.2f s: %.1f ms/frame (%.1f ms writing), %.0f state bytes/frame%s", baked, total,
                  1e3 * total / baked, 1e3 * write_s / baked, double(state_bytes) / baked, o.ply ? "" : "\n");
    std::cout << line;
    if (o.ply) {
      std::snprintf(line, sizeof line, ", %.0f PLY bytes/frame\n", double(ply_bytes) / baked);
      std::cout << line;
    }
  }
  return 0;
}

}  // namespace simreel::app
