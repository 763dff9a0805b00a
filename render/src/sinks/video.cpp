// The video sink (frame_sink.hpp): raw RGBA frames piped to an ffmpeg child process, which
// writes an AtomicFile's temporary; committed only when ffmpeg exits 0.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "ffmpeg.hpp"
#include "simreel/render/atomic_file.hpp"
#include "simreel/render/frame_sink.hpp"

extern char** environ;

namespace simreel::render {

namespace fs = std::filesystem;

namespace {

using detail::find_on_path;

/// A write to a pipe whose reader died raises SIGPIPE, which would kill the program. Blocking
/// it on this thread (instead of changing the process-wide disposition) turns it into EPIPE;
/// a SIGPIPE raised meanwhile is consumed before unblocking.
class SigpipeBlock {
 public:
  SigpipeBlock() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &set_, &old_);
  }
  ~SigpipeBlock() {
    const timespec zero{};
    while (sigtimedwait(&set_, nullptr, &zero) > 0) {
    }
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  SigpipeBlock(const SigpipeBlock&) = delete;
  SigpipeBlock& operator=(const SigpipeBlock&) = delete;

 private:
  sigset_t set_{};
  sigset_t old_{};
};

std::string format_fps(double fps) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, fps);
  return ec == std::errc() ? std::string(buf, end) : std::to_string(fps);
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

/// "4M", "800k", "1500000", "2.5M": digits with at most one point, then an optional k or M.
bool bitrate_syntax(const std::string& text) {
  std::size_t i = 0;
  bool digit = false;
  bool point = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (std::isdigit(static_cast<unsigned char>(c)) != 0) {
      digit = true;
    } else if (c == '.' && !point) {
      point = true;
    } else {
      break;
    }
  }
  if (!digit) return false;
  if (i == text.size()) return true;
  return i + 1 == text.size() && (text[i] == 'k' || text[i] == 'K' || text[i] == 'M');
}

}  // namespace

std::optional<double> video_bitrate(const std::string& text) {
  if (!bitrate_syntax(text)) return std::nullopt;
  const char last = text.back();
  const double scale = last == 'M' ? 1e6 : (last == 'k' || last == 'K') ? 1e3 : 1.0;
  const double bits = std::strtod(text.c_str(), nullptr) * scale;
  if (!(bits >= 1e3 && bits <= 1e10)) return std::nullopt;
  return bits;
}

namespace {

std::uint64_t big_endian(const unsigned char* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

/// "" if the finished file looks whole: not empty; an MP4's top-level boxes tile the file
/// exactly and include "moov" (a full disk cuts the trailer, ffprobe then says "moov atom not
/// found"); a GIF starts with "GIF8" and ends with its 0x3B trailer; a WebM starts with the
/// EBML magic. Otherwise what is wrong.
std::string container_problem(const fs::path& file, const std::string& ext) {
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (f == nullptr) return std::string("cannot read the encoded file: ") + std::strerror(errno);
  std::vector<unsigned char> head(16);
  std::error_code ec;
  const std::uint64_t size = fs::file_size(file, ec);
  std::string problem;
  if (ec || size == 0) {
    problem = "ffmpeg wrote an empty file";
  } else if (ext == ".mp4") {
    bool moov = false;
    std::uint64_t at = 0;
    while (at < size && problem.empty()) {
      if (size - at < 8 || ::fseeko(f, off_t(at), SEEK_SET) != 0 || std::fread(head.data(), 1, 16, f) < 8) {
        problem = "the MP4 ends inside a box header at byte " + std::to_string(at);
        break;
      }
      std::uint64_t box = big_endian(head.data(), 4);
      const std::string type(reinterpret_cast<const char*>(head.data()) + 4, 4);
      if (box == 1) box = size - at >= 16 ? big_endian(head.data() + 8, 8) : 0;
      else if (box == 0) box = size - at;
      if (box < 8 || box > size - at) {
        problem = "the MP4 is cut short: box \"" + type + "\" at byte " + std::to_string(at) + " claims " +
                  std::to_string(box) + " bytes, " + std::to_string(size - at) + " remain";
        break;
      }
      moov = moov || type == "moov";
      at += box;
    }
    if (problem.empty() && !moov) problem = "the MP4 has no \"moov\" box (the trailer was not written)";
  } else if (ext == ".gif") {
    unsigned char last = 0;
    const bool read = std::fread(head.data(), 1, 4, f) == 4 && ::fseeko(f, -1, SEEK_END) == 0 &&
                      std::fread(&last, 1, 1, f) == 1;
    if (!read || std::memcmp(head.data(), "GIF8", 4) != 0 || last != 0x3B)
      problem = "the GIF is incomplete (no signature or no trailer byte)";
  } else if (ext == ".webm") {
    if (std::fread(head.data(), 1, 4, f) != 4 || big_endian(head.data(), 4) != 0x1A45DFA3u)
      problem = "the WebM does not start with the EBML header";
  }
  std::fclose(f);
  return problem;
}

class VideoSink final : public FrameSink {
 public:
  VideoSink(const fs::path& path, int width, int height, const VideoOptions& options)
      : path_(path), ext_(lower_extension(path)), width_(width), height_(height) {
    const std::string& ext = ext_;
    if (ext != ".mp4" && ext != ".gif" && ext != ".webm") {
      fail("unsupported extension \"" + path.extension().string() +
           "\" (expected .mp4, .webm or .gif)");
    }
    if (width < 1 || height < 1) fail("frame size must be at least 1x1");
    if (!(options.fps > 0.0) || !std::isfinite(options.fps)) fail("fps must be positive");
    const int max_crf = ext == ".webm" ? 63 : 51;
    if (options.crf < 0 || options.crf > max_crf) {
      fail("crf must be in 0.." + std::to_string(max_crf));
    }
    if (!options.bitrate.empty() && !video_bitrate(options.bitrate)) {
      fail("bitrate \"" + options.bitrate + "\" is not a number with an optional k or M suffix in [1k, 10000M]");
    }
    const fs::path ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty()) fail("ffmpeg not found on PATH");
    if (ext == ".webm" && !ffmpeg_has_encoder("libvpx-vp9")) {
      fail("this ffmpeg has no VP9 encoder (libvpx-vp9 is not listed by `ffmpeg -encoders`); "
           "write .mp4 instead");
    }

    if (const std::string problem = make_parent_directories(path); !problem.empty()) fail(problem);
    // ffmpeg writes the temporary (-y overwrites the empty file AtomicFile opened); finish()
    // renames it only after ffmpeg exited 0, so a failed or cut video never appears.
    file_.emplace(path);

    std::vector<std::string> args = {ffmpeg.string(), "-hide_banner", "-nostdin", "-loglevel",
                                     "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgba", "-s",
                                     std::to_string(width) + "x" + std::to_string(height), "-r",
                                     format_fps(options.fps), "-i", "-"};
    // A target bit rate replaces constant quality; VP9 needs -b:v 0 for pure constant quality.
    std::vector<std::string> rate = {"-crf", std::to_string(options.crf)};
    if (!options.bitrate.empty()) rate = {"-b:v", options.bitrate};
    if (ext == ".mp4") {
      args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264",
                               "-preset", "veryfast"});
      args.insert(args.end(), rate.begin(), rate.end());
      args.insert(args.end(), {"-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4"});
    } else if (ext == ".webm") {
      if (options.bitrate.empty()) rate.insert(rate.end(), {"-b:v", "0"});
      // yuv420p needs even sizes for the widest player support, as for MP4.
      args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libvpx-vp9",
                               "-deadline", "good", "-cpu-used", "5", "-row-mt", "1"});
      args.insert(args.end(), rate.begin(), rate.end());
      args.insert(args.end(), {"-pix_fmt", options.alpha ? "yuva420p" : "yuv420p", "-f", "webm"});
    } else {
      args.insert(args.end(),
                  {"-vf", "split[a][b];[a]palettegen[p];[b][p]paletteuse", "-f", "gif"});
    }
    args.push_back(file_->temporary().string());
    spawn(ffmpeg, args);
  }

  ~VideoSink() override { abort(); }
  VideoSink(const VideoSink&) = delete;
  VideoSink& operator=(const VideoSink&) = delete;

  void write(const Image& frame, int index) override {
    if (pid_ <= 0) fail("frame " + std::to_string(index) + " written after the video was closed");
    if (frame.width != width_ || frame.height != height_ ||
        frame.rgba.size() != std::size_t(width_) * std::size_t(height_) * 4) {
      fail("frame " + std::to_string(index) + " is " + std::to_string(frame.width) + "x" +
           std::to_string(frame.height) + ", expected " + std::to_string(width_) + "x" +
           std::to_string(height_));
    }
    const std::uint8_t* data = frame.rgba.data();
    std::size_t left = frame.rgba.size();
    int err = 0;
    {
      const SigpipeBlock block;
      while (left > 0) {
        const ssize_t n = ::write(stdin_fd_, data, left);
        if (n < 0) {
          if (errno == EINTR) continue;
          err = errno;
          break;
        }
        data += n;
        left -= std::size_t(n);
      }
    }
    if (err != 0) {
      // ffmpeg went away (bad arguments, disk full, ...): its own message says why.
      const int status = close_and_wait();
      const std::string log = stderr_tail();
      cleanup();
      fail("ffmpeg stopped reading frames at frame " + std::to_string(index) + " (" +
           describe_status(status) + ")" + (log.empty() ? "" : ": " + log));
    }
  }

  void finish() override {
    if (pid_ <= 0) fail("video already closed");
    const int status = close_and_wait();
    const std::string log = stderr_tail();
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      cleanup();
      fail("ffmpeg failed (" + describe_status(status) + ")" + (log.empty() ? "" : ": " + log));
    }
    // ffmpeg 5.1 prints "Error writing trailer: No space left on device" and exits 0: at
    // -loglevel error anything it prints is an error, and the file itself is checked too.
    if (!log.empty()) {
      cleanup();
      fail("ffmpeg reported an error though it exited 0: " + log);
    }
    if (const std::string problem = container_problem(file_->temporary(), ext_); !problem.empty()) {
      cleanup();
      fail(problem);
    }
    close_stderr();
    file_->commit();  // IoError naming the path; the temporary is removed
    file_.reset();
  }

  void abort() noexcept override {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      close_and_wait();
    }
    cleanup();
  }

  [[nodiscard]] std::string describe() const override { return path_.string(); }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw IoError("cannot encode " + path_.string() + ": " + why);
  }

  void spawn(const fs::path& ffmpeg, const std::vector<std::string>& args) {
    // ffmpeg's stderr goes to an unlinked temporary file: nothing to drain while frames are
    // written, nothing left behind, and the parent reads it through its own descriptor.
    std::error_code ec;
    fs::path log_dir = fs::temp_directory_path(ec);
    if (ec) log_dir = "/tmp";
    std::string log_name = (log_dir / "simreel-ffmpeg-XXXXXX").string();
    stderr_fd_ = ::mkostemp(log_name.data(), O_CLOEXEC);
    if (stderr_fd_ < 0) {
      fail("cannot create a log file for ffmpeg in " + log_dir.string() + ": " +
           std::strerror(errno));
    }
    ::unlink(log_name.c_str());

    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
      const int e = errno;
      close_stderr();
      fail(std::string("cannot create a pipe: ") + std::strerror(e));
    }

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, stderr_fd_, 2);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGPIPE);
    sigset_t empty;
    sigemptyset(&empty);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setsigmask(&attr, &empty);
    // Own process group: Ctrl-C at the terminal signals the foreground group, and ffmpeg
    // stopping on its own would cut the video short; simreel closes its input instead.
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setflags(&attr,
                             POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETPGROUP);

    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int rc = ::posix_spawn(&pid, ffmpeg.c_str(), &actions, &attr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    ::close(fds[0]);
    if (rc != 0) {
      ::close(fds[1]);
      close_stderr();
      fail("cannot start " + ffmpeg.string() + ": " + std::strerror(rc));
    }
    pid_ = pid;
    register_child(pid);
    stdin_fd_ = fds[1];
  }

  /// Closes ffmpeg's input and reaps it; returns the wait status.
  int close_and_wait() noexcept {
    if (stdin_fd_ >= 0) {
      ::close(stdin_fd_);
      stdin_fd_ = -1;
    }
    int status = 0;
    if (pid_ > 0) {
      while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
      }
      unregister_child(pid_);
      pid_ = -1;
    }
    return status;
  }

  static std::string describe_status(int status) {
    if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
    return "status " + std::to_string(status);
  }

  /// The last few lines ffmpeg printed, joined into one line.
  std::string stderr_tail() const {
    if (stderr_fd_ < 0) return {};
    std::string text;
    char buf[4096];
    off_t offset = 0;
    for (;;) {
      const ssize_t n = ::pread(stderr_fd_, buf, sizeof buf, offset);
      if (n <= 0) break;
      text.append(buf, std::size_t(n));
      offset += n;
    }
    std::vector<std::string> lines;
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      std::string line = text.substr(start, end - start);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
      if (!line.empty()) lines.push_back(std::move(line));
      start = end + 1;
    }
    constexpr std::size_t kLines = 3;
    std::string tail;
    for (std::size_t i = lines.size() > kLines ? lines.size() - kLines : 0; i < lines.size(); ++i) {
      if (!tail.empty()) tail += " | ";
      tail += lines[i];
    }
    return tail;
  }

  void close_stderr() noexcept {
    if (stderr_fd_ >= 0) {
      ::close(stderr_fd_);
      stderr_fd_ = -1;
    }
  }

  void cleanup() noexcept {
    close_stderr();
    if (file_) file_->discard();
  }

  fs::path path_;
  std::string ext_;  ///< lower-case extension: .mp4, .webm or .gif
  std::optional<AtomicFile> file_;  // engaged once the checks passed
  int width_;
  int height_;
  pid_t pid_ = -1;
  int stdin_fd_ = -1;
  int stderr_fd_ = -1;
};

}  // namespace

std::unique_ptr<FrameSink> make_video(const fs::path& path, int width, int height,
                                      const VideoOptions& options) {
  return std::make_unique<VideoSink>(path, width, height, options);
}

}  // namespace simreel::render
