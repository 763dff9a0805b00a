#pragma once
/// @file sim_cache.hpp
/// The simulation cache of `simreel bake` (docs/cache.md): a folder holding `manifest.json` (what
/// was baked: scene hash, overrides, seed, fps, frames, build) and one file per frame,
/// `state/frame_NNNNN.state`, with the engine's complete state at t = frame / fps
/// (World::save_state) behind a checked header. `simreel render --cache` restores frames from it
/// instead of simulating; `bake --resume` continues from its last complete frame.
///
/// Every file is written atomically (temporary + rename), so a bake killed at any moment leaves
/// only complete files under their final names; a frame file is valid when its header, size and
/// checksum agree with the manifest.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "scene.hpp"

namespace simreel::app {

/// Version of the cache layout (manifest keys, frame header); a reader refuses any other.
inline constexpr int kCacheFormat = 1;

/// What a cache was baked from. Two caches with equal identities hold the same frames.
struct CacheIdentity {
  std::string scene_hash;              ///< FNV-1a 64 of the scene file's bytes, 16 hex digits
  std::vector<std::string> overrides;  ///< --set values in order
  std::uint64_t seed = 0;              ///< the seed used (scene's or --seed)
  double fps = 30.0;                   ///< the sampling rate used (scene's or --fps)
  std::string simreel_version;         ///< the build's version (results differ between builds)
  std::uint32_t state_format = 0;      ///< the engine's state layout
  /// 64-bit key over all of the above: every frame file carries it, so a frame of another bake
  /// copied into the folder is refused.
  [[nodiscard]] std::uint64_t key() const;
};

struct CacheManifest {
  CacheIdentity id;
  std::string scene;    ///< the scene path as given (for people; not compared)
  int frames = 0;       ///< frames 0..frames-1 are baked
  bool complete = false;  ///< the bake finished (false while it runs or after a kill)
  bool ply = false;     ///< PLY interchange files are beside the state files
};

/// FNV-1a 64 of a file's bytes as 16 hex digits. @throws SceneError if it cannot be read.
std::string file_hash(const std::filesystem::path& file);

/// The identity of baking `scene` (prepared with its overrides, --seed and --fps applied) from
/// `scene_file` with `overrides`.
CacheIdentity cache_identity(const Scene& scene, const std::filesystem::path& scene_file,
                             const std::vector<std::string>& overrides);

std::filesystem::path manifest_path(const std::filesystem::path& dir);
std::filesystem::path frame_path(const std::filesystem::path& dir, int frame);
std::filesystem::path ply_dir(const std::filesystem::path& dir);

/// Writes DIR/manifest.json atomically. @throws render::IoError.
void write_manifest(const std::filesystem::path& dir, const CacheManifest& m);
/// Reads DIR/manifest.json. @throws SceneError naming the file and the bad key.
CacheManifest read_manifest(const std::filesystem::path& dir);

/// "" when `found` was baked with `wanted`'s identity; else what differs, e.g.
/// "scene hash 8c1d... differs from the scene's 02ab..." (one clause per difference).
std::string identity_difference(const CacheIdentity& found, const CacheIdentity& wanted);

/// Writes one frame's engine state atomically. @throws render::IoError.
void write_frame(const std::filesystem::path& dir, int frame, std::uint64_t key, const std::string& state,
                 std::string& scratch);

/// Reads frame `frame`'s state into `state`. On a missing, truncated or corrupt file, or one of
/// another bake, returns the reason naming the file (and leaves `state` unspecified); "" if good.
std::string read_frame(const std::filesystem::path& dir, int frame, std::uint64_t key, std::string& state);

/// The header-only check of read_frame (existence, size, key): cheap, for checking a whole range
/// before rendering. "" if good.
std::string check_frame_header(const std::filesystem::path& dir, int frame, std::uint64_t key);

/// Removes temporaries left by a killed writer (".NAME.tmp-*") in the cache's folders.
void remove_stale_temporaries(const std::filesystem::path& dir);

}  // namespace simreel::app
