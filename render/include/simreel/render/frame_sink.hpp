#pragma once
/// @file frame_sink.hpp
/// Where rendered frames go: a PNG sequence or a video through an ffmpeg child process.
/// Every file appears under its final name only when complete (temporary name, then rename).

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "simreel/render/image.hpp"

namespace simreel::render {

class FrameSink {
 public:
  virtual ~FrameSink() = default;  ///< destroying an unfinished sink aborts it (no partial files)
  /// Writes frame number `index` (0-based). @throws IoError naming the file.
  virtual void write(const Image& frame, int index) = 0;
  /// Completes the output (closes the video, renames to the final name). @throws IoError.
  virtual void finish() = 0;
  /// Discards unfinished output; never throws.
  virtual void abort() noexcept = 0;
  [[nodiscard]] virtual std::string describe() const = 0;  ///< e.g. "out/fountain.mp4"
};

/// PNG sequence `dir/frame_00000.png`, ... (directory created if missing). Each frame is written
/// atomically, so finish() and abort() have nothing to do and written frames stay.
/// @throws IoError if the directory cannot be created.
std::unique_ptr<FrameSink> make_png_sequence(const std::filesystem::path& dir, int compression = 4);

struct VideoOptions {
  double fps = 30.0;
  int crf = 18;  ///< H.264 constant rate factor (0–51, lower is better)
};

/// MP4 (H.264, yuv420p, odd sizes padded to even) or GIF (palette generated from the frames),
/// chosen by the extension, through `ffmpeg` fed raw RGBA frames on a pipe.
/// The parent directory is created if missing; frames must be width x height. ffmpeg's stderr
/// is captured and its last lines end any IoError that write() or finish() raise.
/// @throws IoError with one line if ffmpeg cannot be found or started, or the extension is
///         neither .mp4 nor .gif, e.g. "cannot encode out/x.mp4: ffmpeg not found on PATH".
std::unique_ptr<FrameSink> make_video(const std::filesystem::path& path, int width, int height,
                                      const VideoOptions& options);

/// True when an `ffmpeg` executable is on PATH.
bool ffmpeg_available();

}  // namespace simreel::render
