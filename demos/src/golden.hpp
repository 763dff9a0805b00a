#pragma once
/// @file golden.hpp
/// Hash records: the per-frame image hashes of a render together with everything needed to
/// render it again (scene, --set overrides, seed, size, fps, frame range, backend) and the
/// machine that made it. `simreel render --hash FILE` writes one; the same file is a golden
/// that `simreel check` re-renders and compares by Hamming distance.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "simreel/render/atomic_file.hpp"
#include "simreel/render/frame_sink.hpp"
#include "simreel/render/image.hpp"

namespace simreel::app {

/// The three 64-bit hashes of one frame (render/image_hash.hpp).
struct FrameHashes {
  int frame = 0;
  std::uint64_t phash = 0;
  std::uint64_t dhash = 0;
  std::uint64_t chash = 0;
};

FrameHashes hash_frame(const render::Image& image, int frame);

/// Largest Hamming distance accepted per hash kind. Defaults leave room for the small
/// differences between Mesa versions and CPUs; a changed effect moves 15+ bits.
struct Tolerance {
  int phash = 8;
  int dhash = 8;
  int chash = 4;
};

/// "simreel_hashes" in the file. 2: "scene" is relative to the golden file's folder (or
/// absolute). 1 (older records, still read): "scene" is the path given to `render`, relative to
/// the directory it ran in; `check` looks beside the golden first, then in the working directory.
inline constexpr int kHashFormat = 2;

struct HashRecord {
  int format = kHashFormat;            ///< 1 or 2, kept by `check --update`
  std::string scene;                   ///< see kHashFormat
  std::vector<std::string> overrides;  ///< --set POINTER=VALUE, in order
  long long seed = 0;
  int width = 0;
  int height = 0;
  double fps = 30.0;
  int first = 0;  ///< frames [first, end) were rendered; the simulation starts at frame 0
  int end = 0;
  int every = 1;  ///< frames first, first + every, ... are hashed
  std::string backend = "osmesa";
  Tolerance tolerance;
  std::string simreel_version;
  std::string gl_renderer;
  std::string gl_version;
  std::string note;  ///< free text kept as is (e.g. what the recorder saw in the frames)
  std::vector<FrameHashes> frames;
};

/// True for the frames a record with this range and step hashes.
bool is_hashed_frame(const HashRecord& record, int frame);

nlohmann::ordered_json to_json(const HashRecord& record);
/// Reads a hash record / golden, checking every key like a scene file.
/// @throws SceneError (exit 2) naming the file and JSON pointer.
HashRecord read_hash_record(const std::filesystem::path& path);
/// The one atomic-write helper (render/atomic_file.hpp): temporary name, fsync, rename.
/// @throws render::IoError naming the path.
using render::write_file_atomic;

/// A FrameSink that hashes the frames `record` selects and, on finish(), writes the record
/// with them to `path` atomically. abort() writes nothing.
std::unique_ptr<render::FrameSink> make_hash_recorder(const std::filesystem::path& path,
                                                      HashRecord record);

/// The "scene" to store in a format-2 record written to `golden`: `scene` (as given on the
/// command line, relative to the working directory) made relative to the golden's folder, e.g.
/// scene "scenes/a.json", golden "goldens/a.json" -> "../scenes/a.json".
std::string scene_relative_to_golden(const std::filesystem::path& scene, const std::filesystem::path& golden);

/// Directory of a golden's reference frames: `tests/golden/x.json` -> `tests/golden/x.frames`.
std::filesystem::path golden_frames_dir(const std::filesystem::path& golden);

}  // namespace simreel::app
