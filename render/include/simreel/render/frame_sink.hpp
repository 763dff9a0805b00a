#pragma once
/// @file frame_sink.hpp
/// Where rendered frames go: a PNG sequence, a video through an ffmpeg child process, a contact
/// sheet; and FrameWriter, which feeds sinks from writer threads through a bounded queue.
/// Every file appears under its final name only when complete: each is written through
/// AtomicFile (atomic_file.hpp: temporary name, fsync, rename).

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <optional>
#include <string>
#include <thread>
#include <vector>

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
  /// How many FrameWriter threads may call write() at once, each with a different frame. 1 (the
  /// default): frames arrive one at a time, in order (a video, a sheet). A sink whose frames are
  /// independent files (a PNG sequence) returns more, so that encoding keeps up with a GPU.
  [[nodiscard]] virtual int concurrency() const { return 1; }
};

/// PNG sequence `dir/frame_00000.png`, ... (directory created if missing). Each frame is written
/// atomically, so finish() and abort() have nothing to do and written frames stay. `threads`:
/// how many frames a FrameWriter may compress at once (concurrency()); 0 = min(4, cores). A
/// 1280x720 frame takes ~50 ms to compress at level 1, which held a GPU's 40-135 frames/s to
/// 20 with one thread. The bytes of each file do not depend on it.
/// @throws IoError if the directory cannot be created.
std::unique_ptr<FrameSink> make_png_sequence(const std::filesystem::path& dir, int compression = 4,
                                             int threads = 0);

struct VideoOptions {
  double fps = 30.0;
  /// Constant rate factor: H.264 0–51 (lower is better); for WebM (VP9, 0–63) the same number
  /// is used. Ignored when `bitrate` is set.
  int crf = 18;
  /// Target bit rate as ffmpeg spells it ("4M", "800k"); empty = constant quality (`crf`).
  std::string bitrate;
  /// Keep the frames' alpha (RenderSettings Background::transparent): a .webm is then VP9 with
  /// an alpha channel (yuva420p, ffprobe shows the tag alpha_mode=1); .mp4 and .gif drop it.
  bool alpha = false;
};

/// The bits per second of a VideoOptions::bitrate ("4M" = 4e6, "800k", "1500000", "2.5M"), or
/// nothing when it is not digits with at most one point and an optional k, K or M suffix, or lies
/// outside [1 kbit/s, 10 Gbit/s] ("0k" was handed to ffmpeg, which took it as no target at all).
std::optional<double> video_bitrate(const std::string& text);

/// A video through `ffmpeg` fed raw RGBA frames on a pipe, chosen by the extension
/// (case-insensitive):
///  - .mp4:  H.264 (libx264, preset veryfast), yuv420p, odd sizes padded to even, faststart;
///  - .webm: VP9 (libvpx-vp9), yuv420p (yuva420p with VideoOptions::alpha); needs an ffmpeg
///           built with libvpx;
///  - .gif:  two passes over the frames inside ffmpeg: palettegen builds one 256-colour palette
///           from all frames, paletteuse dithers every frame with it.
/// The parent directory is created if missing; frames must be width x height. ffmpeg runs in
/// its own process group, so a Ctrl-C at the terminal reaches only simreel, which then closes
/// the video properly. ffmpeg's stderr is captured and its last lines end any IoError that
/// write() or finish() raise. @throws IoError with one line if ffmpeg cannot be found or
/// started, lacks the encoder, the extension is not one of the above or `bitrate` is not a
/// number with an optional k/M suffix in [1k, 10000M] (video_bitrate), e.g. "cannot encode out/x.mp4: ffmpeg not found on PATH".
std::unique_ptr<FrameSink> make_video(const std::filesystem::path& path, int width, int height,
                                      const VideoOptions& options);

/// True when an `ffmpeg` executable is on PATH.
bool ffmpeg_available();
/// True when `ffmpeg -encoders` lists `name` (e.g. "libvpx-vp9"); false without ffmpeg.
bool ffmpeg_has_encoder(const std::string& name);

/// Geometry of a contact sheet: which frames it shows and how big the thumbnails are.
struct ContactSheetLayout {
  int columns = 4;
  int rows = 4;
  int thumb_width = 320;  ///< pixels; the height follows the frame's aspect ratio
  int gap = 4;            ///< pixels between and around thumbnails
};

/// Frame indices of a sheet with `cells` thumbnails sampled evenly from [first, first + count):
/// the first and the last frame always included, rounded to nearest; fewer when count < cells.
/// @throws std::invalid_argument if cells < 1 or count < 1.
std::vector<int> contact_sheet_frames(int first, int count, int cells);

/// One PNG with thumbnails of the frames in `frames` (in that order, row by row), each labelled
/// with its frame number. Frames not listed are ignored; a listed frame that never arrives
/// leaves its cell dark. Only the sheet is held in memory. @throws IoError if the parent
/// directory cannot be created; std::invalid_argument for a bad layout.
std::unique_ptr<FrameSink> make_contact_sheet(const std::filesystem::path& path, int width,
                                              int height, std::vector<int> frames,
                                              const ContactSheetLayout& layout);

/// Feeds frames to several sinks, each on its own writer thread (FrameSink::concurrency() threads
/// for a sink that allows more), so PNG compression and the pipe to ffmpeg run beside simulation
/// and rendering. Each sink holds at most `depth` + concurrency() - 1 frames, queued or being
/// written; write() blocks while any is full, so memory stays bounded however long the video
/// (frames are shared between the queues, not copied). A sink of concurrency 1 sees the frames in
/// the order written; one of more sees them in any order, each frame once; either way the output
/// bytes do not depend on timing. Frames may be skipped (a range, a sheet); sinks see the indices
/// they are given.
///
/// A sink whose write or finish throws IoError is aborted (no partial file) and dropped; the
/// error is kept for failures(). Not thread-safe itself: one producer thread calls write() and
/// finish().
class FrameWriter {
 public:
  struct Failure {
    std::string output;   ///< the sink's describe()
    std::string message;  ///< the IoError's text
  };

  /// depth 0: no threads, every sink is written inside write() (for measurements).
  explicit FrameWriter(std::vector<std::unique_ptr<FrameSink>> sinks, std::size_t depth = 4);
  ~FrameWriter();  ///< aborts whatever is not finished
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  /// Queues frame `index` for every live sink; blocks while a queue holds `depth` frames.
  void write(Image frame, int index);
  /// The same frame may be handed to several writers without a copy.
  void write(std::shared_ptr<const Image> frame, int index);
  /// Drains the queues, finishes every sink (closes videos, renames files) and joins the
  /// threads. Returns the outputs completed, in the order given.
  std::vector<std::string> finish();
  /// Sinks that failed so far (write or finish), oldest first; each is reported once.
  std::vector<Failure> take_failures();

 private:
  struct Item {
    std::shared_ptr<const Image> frame;
    int index = 0;
  };
  struct Lane {
    std::unique_ptr<FrameSink> sink;
    std::deque<Item> queue;
    std::vector<std::thread> threads;
    std::size_t capacity = 0;   ///< queued + in_flight at most
    std::size_t in_flight = 0;  ///< frames taken off the queue and being written
    int running = 0;            ///< threads not yet returned; the last one finishes the sink
    bool failed = false;
    bool finished = false;
  };
  void run(Lane& lane);

  std::vector<std::unique_ptr<Lane>> lanes_;
  std::size_t depth_;
  std::mutex mutex_;
  std::condition_variable work_;   ///< producer -> writers: an item or closing
  std::condition_variable space_;  ///< writers -> producer: a queue has room
  bool closing_ = false;
  bool aborting_ = false;
  std::vector<Failure> failures_;
};

}  // namespace simreel::render
