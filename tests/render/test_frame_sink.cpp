// Frame sinks: PNG sequences, MP4/GIF through ffmpeg, and no partial files on failure or abort.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>

#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "render_test_util.hpp"
#include "simreel/render/frame_sink.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/text_overlay.hpp"

namespace simreel::render {
namespace {

namespace fs = std::filesystem;

Image frame(int w, int h, int t) {
  Image img(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = img.pixel(x, y);
      p[0] = std::uint8_t((x * 255) / w);
      p[1] = std::uint8_t((y * 255) / h);
      p[2] = std::uint8_t(t * 20);
      p[3] = 255;
    }
  }
  return img;
}

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) out += buf;
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r' || out.back() == ' ')) out.pop_back();
  return out;
}

/// Sets PATH for the scope of the object and restores it afterwards.
class ScopedPath {
 public:
  explicit ScopedPath(const std::string& value) {
    if (const char* old = std::getenv("PATH")) old_ = old;
    ::setenv("PATH", value.c_str(), 1);
  }
  ~ScopedPath() {
    if (old_) {
      ::setenv("PATH", old_->c_str(), 1);
    } else {
      ::unsetenv("PATH");
    }
  }
  ScopedPath(const ScopedPath&) = delete;
  ScopedPath& operator=(const ScopedPath&) = delete;

 private:
  std::optional<std::string> old_;
};

TEST(RenderPngSequence, WritesNumberedFramesIntoANewDirectory) {
  const test::TempDir dir("seq");
  const fs::path out = dir.path() / "frames" / "run1";
  auto sink = make_png_sequence(out);
  for (int i = 0; i < 3; ++i) sink->write(frame(20, 10, i), i);
  sink->finish();
  EXPECT_TRUE(fs::exists(out / "frame_00000.png"));
  EXPECT_TRUE(fs::exists(out / "frame_00002.png"));
  EXPECT_EQ(read_image(out / "frame_00001.png").rgba, frame(20, 10, 1).rgba);
  EXPECT_NE(sink->describe().find("frame_"), std::string::npos);
}

TEST(RenderVideo, Mp4AtAnOddSizeIsPaddedToEvenYuv420p) {
  ASSERT_TRUE(ffmpeg_available());
  const test::TempDir dir("mp4");
  const fs::path path = dir.path() / "clip.mp4";
  auto sink = make_video(path, 161, 121, VideoOptions{10.0, 23, ""});
  EXPECT_EQ(sink->describe(), path.string());
  for (int i = 0; i < 10; ++i) sink->write(frame(161, 121, i), i);
  EXPECT_FALSE(fs::exists(path));  // only under a temporary name until finished
  sink->finish();
  ASSERT_TRUE(fs::exists(path));
  EXPECT_EQ(dir.entries(), 1);
  EXPECT_EQ(run("ffprobe -v error -show_entries stream=width,height,pix_fmt -of csv=p=0 '" +
                path.string() + "'"),
            "162,122,yuv420p");
  EXPECT_EQ(run("ffprobe -v error -count_frames -show_entries stream=nb_read_frames -of csv=p=0 '" +
                path.string() + "'"),
            "10");
}

TEST(RenderVideo, GifStartsWithTheGifSignature) {
  ASSERT_TRUE(ffmpeg_available());
  const test::TempDir dir("gif");
  const fs::path path = dir.path() / "clip.GIF";
  auto sink = make_video(path, 40, 30, VideoOptions{});
  for (int i = 0; i < 5; ++i) sink->write(frame(40, 30, i), i);
  sink->finish();
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  EXPECT_EQ(std::string(magic, 4), "GIF8");
  EXPECT_EQ(dir.entries(), 1);
}

TEST(RenderVideo, AbortAndDestructionLeaveNoFile) {
  ASSERT_TRUE(ffmpeg_available());
  const test::TempDir dir("abort");
  {
    auto sink = make_video(dir.path() / "a.mp4", 32, 32, VideoOptions{});
    for (int i = 0; i < 3; ++i) sink->write(frame(32, 32, i), i);
    sink->abort();
    sink->abort();  // idempotent
  }
  {
    auto sink = make_video(dir.path() / "b.gif", 32, 32, VideoOptions{});
    sink->write(frame(32, 32, 0), 0);
  }  // destroyed unfinished
  EXPECT_EQ(dir.entries(), 0);
}

TEST(RenderVideo, MissingFfmpegIsOneClearError) {
  const test::TempDir empty("nopath");
  const ScopedPath path(empty.path().string());
  EXPECT_FALSE(ffmpeg_available());
  try {
    (void)make_video("out/x.mp4", 16, 16, VideoOptions{});
    FAIL() << "make_video succeeded without ffmpeg";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot encode out/x.mp4: ffmpeg not found on PATH");
  }
}

TEST(RenderVideo, UnsupportedExtensionIsRejected) {
  try {
    (void)make_video("out/x.avi", 16, 16, VideoOptions{});
    FAIL() << "make_video accepted .avi";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("out/x.avi"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists("out/x.avi"));
}

TEST(RenderVideo, FfmpegFailureCarriesItsMessageAndLeavesNoFile) {
  // A stand-in ffmpeg that reads nothing and fails: writes hit a closed pipe (no SIGPIPE
  // death) or finish() sees the exit code; either way its stderr reaches the error.
  const test::TempDir bin("fakebin");
  const fs::path fake = bin.path() / "ffmpeg";
  std::ofstream(fake) << "#!/bin/sh\necho 'fake failure: no encoder here' >&2\nexit 3\n";
  fs::permissions(fake, fs::perms::owner_all);
  const test::TempDir dir("fail");
  const ScopedPath path(bin.path().string() + ":/usr/bin:/bin");
  std::string message;
  try {
    auto sink = make_video(dir.path() / "x.mp4", 128, 128, VideoOptions{});
    for (int i = 0; i < 20; ++i) sink->write(frame(128, 128, i), i);
    sink->finish();
  } catch (const IoError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("fake failure: no encoder here"), std::string::npos) << message;
  EXPECT_NE(message.find("x.mp4"), std::string::npos) << message;
  EXPECT_EQ(dir.entries(), 0);
}

TEST(RenderVideo, AnFfmpegErrorOrACutFileFailsEvenWhenFfmpegExitsZero) {
  // ffmpeg 5.1 on a full disk: "Error writing trailer: No space left on device", exit code 0,
  // and an MP4 without its "moov" box. Each stand-in exits 0; none may leave a file behind.
  const std::string truncated =
      "printf '\\000\\000\\000\\030ftypisom\\000\\000\\002\\000isomiso2\\000\\000\\010\\000mdat' > \"$last\"\n";
  const std::string whole_without_moov =
      "printf '\\000\\000\\000\\030ftypisom\\000\\000\\002\\000isomiso2\\000\\000\\000\\010free' > \"$last\"\n";
  struct Case {
    std::string body;
    std::string expected;
  };
  const Case cases[] = {
      {truncated + "echo 'Error writing trailer: No space left on device' >&2\n", "No space left on device"},
      {truncated, "cut short"},
      {whole_without_moov, "no \"moov\" box"},
      {": > \"$last\"\n", "empty file"},
  };
  for (const Case& c : cases) {
    const test::TempDir bin("fakebin-full");
    const fs::path fake = bin.path() / "ffmpeg";
    std::ofstream(fake) << "#!/bin/sh\ncat > /dev/null\nfor last; do :; done\n" << c.body << "exit 0\n";
    fs::permissions(fake, fs::perms::owner_all);
    const test::TempDir dir("full");
    const ScopedPath path(bin.path().string() + ":/usr/bin:/bin");
    std::string message;
    try {
      auto sink = make_video(dir.path() / "x.mp4", 32, 32, VideoOptions{});
      for (int i = 0; i < 3; ++i) sink->write(frame(32, 32, i), i);
      sink->finish();
    } catch (const IoError& e) {
      message = e.what();
    }
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.body << ": " << message;
    EXPECT_NE(message.find("x.mp4"), std::string::npos) << message;
    EXPECT_EQ(dir.entries(), 0) << "no video and no temporary: " << c.body;
  }
  // A GIF without its trailer byte is refused the same way.
  const test::TempDir bin("fakebin-gif");
  std::ofstream(bin.path() / "ffmpeg") << "#!/bin/sh\ncat > /dev/null\nfor last; do :; done\nprintf 'GIF89a' > \"$last\"\n";
  fs::permissions(bin.path() / "ffmpeg", fs::perms::owner_all);
  const test::TempDir dir("gif-cut");
  const ScopedPath path(bin.path().string() + ":/usr/bin:/bin");
  auto sink = make_video(dir.path() / "x.gif", 32, 32, VideoOptions{});
  sink->write(frame(32, 32, 0), 0);
  EXPECT_THROW(sink->finish(), IoError);
  EXPECT_EQ(dir.entries(), 0);
}

TEST(RenderVideo, AFailedEncodeKeepsThePreviousVideoAndASuccessfulOneReplacesIt) {
  // ffmpeg writes AtomicFile's temporary: the final name changes only when ffmpeg exited 0.
  const test::TempDir dir("replace");
  const fs::path out = dir.path() / "x.mp4";
  std::ofstream(out) << "previous video";
  {
    const test::TempDir bin("fakebin-replace");
    const fs::path fake = bin.path() / "ffmpeg";
    std::ofstream(fake) << "#!/bin/sh\ncat > /dev/null\necho 'fake failure' >&2\nexit 1\n";
    fs::permissions(fake, fs::perms::owner_all);
    const ScopedPath path(bin.path().string() + ":/usr/bin:/bin");
    auto sink = make_video(out, 32, 32, VideoOptions{});
    sink->write(frame(32, 32, 0), 0);
    EXPECT_THROW(sink->finish(), IoError);
  }
  std::ifstream in(out);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "previous video");
  EXPECT_EQ(dir.entries(), 1);
  ASSERT_TRUE(ffmpeg_available());
  auto sink = make_video(out, 32, 32, VideoOptions{});
  for (int i = 0; i < 3; ++i) sink->write(frame(32, 32, i), i);
  sink->finish();
  EXPECT_GT(fs::file_size(out), 100u);
  EXPECT_EQ(dir.entries(), 1);
}

TEST(RenderVideo, WebmIsVp9WhenTheEncoderExists) {
  ASSERT_TRUE(ffmpeg_available());
  const test::TempDir dir("webm");
  const fs::path path = dir.path() / "clip.webm";
  if (!ffmpeg_has_encoder("libvpx-vp9")) {
    // Without the encoder, the clear error is what a user gets, and what is checked.
    EXPECT_THROW((void)make_video(path, 32, 32, VideoOptions{}), IoError);
    return;
  }
  auto sink = make_video(path, 63, 35, VideoOptions{10.0, 30, ""});
  for (int i = 0; i < 5; ++i) sink->write(frame(63, 35, i), i);
  sink->finish();
  EXPECT_EQ(run("ffprobe -v error -show_entries stream=codec_name,width,height,pix_fmt -of csv=p=0 '" +
                path.string() + "'"),
            "vp9,64,36,yuv420p");
  EXPECT_FALSE(ffmpeg_has_encoder("no-such-encoder"));
}

TEST(RenderVideo, WebmKeepsAlphaWhenAsked) {
  ASSERT_TRUE(ffmpeg_available());
  if (!ffmpeg_has_encoder("libvpx-vp9")) GTEST_SKIP() << "this ffmpeg has no libvpx-vp9";
  const test::TempDir dir("webm-alpha");
  const fs::path path = dir.path() / "clip.webm";
  VideoOptions options{10.0, 30, ""};
  options.alpha = true;
  auto sink = make_video(path, 64, 36, options);
  for (int i = 0; i < 5; ++i) {
    Image f = frame(64, 36, i);
    for (int y = 0; y < 36; ++y) {
      for (int x = 0; x < 32; ++x) f.rgba[(std::size_t(y) * 64 + x) * 4 + 3] = 0;  // left half clear
    }
    sink->write(f, i);
  }
  sink->finish();
  EXPECT_EQ(run("ffprobe -v error -show_entries stream_tags=alpha_mode -of csv=p=0 '" + path.string() + "'"), "1");
  // Decoded with libvpx, the alpha comes back: clear on the left, opaque on the right.
  const std::string alpha = run("ffmpeg -v error -c:v libvpx-vp9 -i '" + path.string() +
                                "' -frames:v 1 -vf alphaextract,scale=2:1:flags=area -f rawvideo -pix_fmt gray - | od -An -tu1");
  int left = -1, right = -1;
  std::sscanf(alpha.c_str(), "%d %d", &left, &right);
  EXPECT_LT(left, 16) << alpha;
  EXPECT_GT(right, 239) << alpha;
}

TEST(RenderVideo, BitrateReplacesCrfAndIsChecked) {
  ASSERT_TRUE(ffmpeg_available());
  const test::TempDir dir("rate");
  // A tiny bit rate gives a much smaller file than the best constant quality.
  auto encode = [&](const std::string& name, VideoOptions options) {
    auto sink = make_video(dir.path() / name, 160, 120, options);
    for (int i = 0; i < 30; ++i) sink->write(frame(160, 120, i % 13), i);
    sink->finish();
    return fs::file_size(dir.path() / name);
  };
  const auto small = encode("low.mp4", VideoOptions{30.0, 0, "20k"});
  const auto large = encode("crf0.mp4", VideoOptions{30.0, 0, ""});
  EXPECT_LT(small * 3, large);
  EXPECT_THROW((void)make_video(dir.path() / "x.mp4", 16, 16, VideoOptions{30.0, 18, "fast"}), IoError);
  // "0k" went to ffmpeg, which reads a zero target as none (the file came out at constant
  // quality); the rate is bounded to [1 kbit/s, 10 Gbit/s].
  EXPECT_THROW((void)make_video(dir.path() / "x.mp4", 16, 16, VideoOptions{30.0, 18, "0k"}), IoError);
  EXPECT_EQ(video_bitrate("2.5M"), 2.5e6);
  EXPECT_EQ(video_bitrate("800k"), 8e5);
  EXPECT_EQ(video_bitrate("1000"), 1e3);
  for (const char* bad : {"0k", "999", "10001M", "1.2.3M", "4G", "", "M", "-1M", "4M "})
    EXPECT_FALSE(video_bitrate(bad).has_value()) << bad;
}

// ---------------------------------------------------------------------------------------------
// FrameWriter

/// Records what it is given; can be told to block in write() or to fail at a frame.
class ProbeSink final : public FrameSink {
 public:
  struct Log {
    std::mutex mutex;
    std::condition_variable changed;
    std::vector<int> indices;
    std::vector<std::uint8_t> first_bytes;
    bool finished = false;
    bool aborted = false;
    bool hold = false;  ///< write() waits while true
  };
  ProbeSink(std::shared_ptr<Log> log, int fail_at = -1) : log_(std::move(log)), fail_at_(fail_at) {}
  void write(const Image& image, int index) override {
    std::unique_lock lock(log_->mutex);
    log_->changed.wait(lock, [&] { return !log_->hold; });
    if (index == fail_at_) throw IoError("probe: disk full at frame " + std::to_string(index));
    log_->indices.push_back(index);
    log_->first_bytes.push_back(image.rgba[2]);
  }
  void finish() override {
    const std::lock_guard lock(log_->mutex);
    log_->finished = true;
  }
  void abort() noexcept override {
    const std::lock_guard lock(log_->mutex);
    log_->aborted = true;
  }
  [[nodiscard]] std::string describe() const override { return "probe"; }

 private:
  std::shared_ptr<Log> log_;
  int fail_at_;
};

TEST(RenderFrameWriter, EverySinkSeesEveryFrameInOrder) {
  for (const std::size_t depth : {std::size_t{0}, std::size_t{1}, std::size_t{4}}) {
    auto a = std::make_shared<ProbeSink::Log>();
    auto b = std::make_shared<ProbeSink::Log>();
    std::vector<std::unique_ptr<FrameSink>> sinks;
    sinks.push_back(std::make_unique<ProbeSink>(a));
    sinks.push_back(std::make_unique<ProbeSink>(b));
    FrameWriter writer(std::move(sinks), depth);
    for (int i = 0; i < 12; ++i) writer.write(frame(8, 8, i), 100 + i);
    const auto done = writer.finish();
    EXPECT_EQ(done.size(), 2u);
    std::vector<int> expected;
    for (int i = 0; i < 12; ++i) expected.push_back(100 + i);
    EXPECT_EQ(a->indices, expected) << depth;
    EXPECT_EQ(b->indices, expected) << depth;
    for (int i = 0; i < 12; ++i) EXPECT_EQ(a->first_bytes[std::size_t(i)], std::uint8_t(i * 20));
    EXPECT_TRUE(a->finished && b->finished);
    EXPECT_TRUE(writer.take_failures().empty());
  }
}

TEST(RenderFrameWriter, QueueIsBoundedWhileASinkIsSlow) {
  auto log = std::make_shared<ProbeSink::Log>();
  log->hold = true;
  std::vector<std::unique_ptr<FrameSink>> sinks;
  sinks.push_back(std::make_unique<ProbeSink>(log));
  FrameWriter writer(std::move(sinks), 3);
  std::atomic<int> queued{0};
  std::thread producer([&] {
    for (int i = 0; i < 10; ++i) {
      writer.write(frame(8, 8, i), i);
      ++queued;
    }
  });
  // The sink holds its first frame: at most depth frames are queued behind it, so the
  // producer stops after 3 writes (or 4 if the writer took one off the queue). Wait for the
  // first 3 (no deadline that load could break), then give it time to overrun the bound.
  for (int i = 0; i < 2000 && queued.load() < 3; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_LE(queued.load(), 4);
  EXPECT_GE(queued.load(), 3);
  {
    const std::lock_guard lock(log->mutex);
    log->hold = false;
  }
  log->changed.notify_all();
  producer.join();
  writer.finish();
  EXPECT_EQ(log->indices.size(), 10u);
}

TEST(RenderFrameWriter, AFailingSinkIsAbortedAndReportedOthersContinue) {
  auto bad = std::make_shared<ProbeSink::Log>();
  auto good = std::make_shared<ProbeSink::Log>();
  std::vector<std::unique_ptr<FrameSink>> sinks;
  sinks.push_back(std::make_unique<ProbeSink>(bad, 3));
  sinks.push_back(std::make_unique<ProbeSink>(good));
  FrameWriter writer(std::move(sinks), 2);
  for (int i = 0; i < 8; ++i) writer.write(frame(8, 8, i), i);
  const auto done = writer.finish();
  ASSERT_EQ(done.size(), 1u);
  const auto failures = writer.take_failures();
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_EQ(failures[0].message, "probe: disk full at frame 3");
  EXPECT_TRUE(bad->aborted);
  EXPECT_FALSE(bad->finished);
  EXPECT_EQ(bad->indices, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(good->indices.size(), 8u);
  EXPECT_TRUE(writer.take_failures().empty()) << "each failure is reported once";
}

TEST(RenderFrameWriter, DestroyedUnfinishedAbortsEverySink) {
  auto log = std::make_shared<ProbeSink::Log>();
  {
    std::vector<std::unique_ptr<FrameSink>> sinks;
    sinks.push_back(std::make_unique<ProbeSink>(log));
    FrameWriter writer(std::move(sinks), 4);
    writer.write(frame(8, 8, 0), 0);
  }
  EXPECT_TRUE(log->aborted);
  EXPECT_FALSE(log->finished);
}

/// A sink that lets `width` threads write at once and records how many did: each write() waits
/// (up to 10 s once, so a broken writer fails the test instead of hanging it) until `width` writes
/// are in progress, or the frames run out.
class ConcurrentProbe final : public FrameSink {
 public:
  struct Log {
    std::mutex mutex;
    std::condition_variable changed;
    std::vector<int> indices;
    int active = 0;
    int max_active = 0;
    int finishes = 0;
    int aborts = 0;
    int frames_left = 0;
    bool gave_up = false;
  };
  ConcurrentProbe(std::shared_ptr<Log> log, int width, int fail_at = -1)
      : log_(std::move(log)), width_(width), fail_at_(fail_at) {}
  void write(const Image&, int index) override {
    std::unique_lock lock(log_->mutex);
    ++log_->active;
    log_->max_active = std::max(log_->max_active, log_->active);
    log_->changed.notify_all();
    if (!log_->gave_up &&
        !log_->changed.wait_for(lock, std::chrono::seconds(10), [&] {
          return log_->max_active >= width_ || log_->frames_left <= log_->active;
        })) {
      log_->gave_up = true;  // one timeout is enough to fail; the rest need not wait
    }
    --log_->active;
    --log_->frames_left;
    if (index == fail_at_) throw IoError("probe: disk full at frame " + std::to_string(index));
    log_->indices.push_back(index);
  }
  void finish() override {
    const std::lock_guard lock(log_->mutex);
    ++log_->finishes;
  }
  void abort() noexcept override {
    const std::lock_guard lock(log_->mutex);
    ++log_->aborts;
  }
  [[nodiscard]] std::string describe() const override { return "concurrent probe"; }
  [[nodiscard]] int concurrency() const override { return width_; }

 private:
  std::shared_ptr<Log> log_;
  int width_;
  int fail_at_;
};

TEST(RenderFrameWriter, AConcurrentSinkGetsEveryFrameOnceFromSeveralThreadsAndOneFinish) {
  auto log = std::make_shared<ConcurrentProbe::Log>();
  log->frames_left = 24;
  auto order = std::make_shared<ProbeSink::Log>();
  std::vector<std::unique_ptr<FrameSink>> sinks;
  sinks.push_back(std::make_unique<ConcurrentProbe>(log, 3));
  sinks.push_back(std::make_unique<ProbeSink>(order));
  FrameWriter writer(std::move(sinks), 2);
  for (int i = 0; i < 24; ++i) writer.write(frame(8, 8, i), i);
  const auto done = writer.finish();
  EXPECT_EQ(done.size(), 2u);
  EXPECT_EQ(log->max_active, 3) << "three frames were being written at once";
  std::vector<int> seen = log->indices;
  std::sort(seen.begin(), seen.end());
  std::vector<int> expected(24);
  for (int i = 0; i < 24; ++i) expected[std::size_t(i)] = i;
  EXPECT_EQ(seen, expected) << "every frame exactly once";
  EXPECT_EQ(order->indices, expected) << "a concurrency-1 sink beside it still sees them in order";
  EXPECT_EQ(log->finishes, 1);
  EXPECT_EQ(log->aborts, 0);
}

TEST(RenderFrameWriter, AFailingConcurrentSinkIsAbortedOnceAndNeverFinished) {
  auto log = std::make_shared<ConcurrentProbe::Log>();
  log->frames_left = 16;
  std::vector<std::unique_ptr<FrameSink>> sinks;
  sinks.push_back(std::make_unique<ConcurrentProbe>(log, 3, 5));
  FrameWriter writer(std::move(sinks), 2);
  for (int i = 0; i < 16; ++i) writer.write(frame(8, 8, i), i);
  const auto done = writer.finish();
  EXPECT_TRUE(done.empty());
  const auto failures = writer.take_failures();
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_EQ(failures[0].message, "probe: disk full at frame 5");
  EXPECT_EQ(log->aborts, 1);
  EXPECT_EQ(log->finishes, 0);
  EXPECT_LT(log->indices.size(), 16u);
}

TEST(RenderFrameWriter, PngBytesDoNotDependOnThreads) {
  const test::TempDir dir("det");
  // depth 0: on the caller's thread; 4: one writer thread; 5: four threads compressing at once.
  for (const std::size_t depth : {std::size_t{0}, std::size_t{4}, std::size_t{5}}) {
    const int threads = depth == 5 ? 4 : 1;
    std::vector<std::unique_ptr<FrameSink>> sinks;
    sinks.push_back(make_png_sequence(dir.path() / std::to_string(depth), 1, threads));
    sinks.push_back(make_png_sequence(dir.path() / (std::to_string(depth) + "b"), 9, threads));
    FrameWriter writer(std::move(sinks), depth);
    for (int i = 0; i < 6; ++i) writer.write(frame(64, 40, i), i);
    EXPECT_EQ(writer.finish().size(), 2u);
  }
  for (const char* name : {"frame_00000.png", "frame_00005.png"}) {
    const auto bytes = [&](const std::string& sub) {
      std::ifstream in(dir.path() / sub / name, std::ios::binary);
      return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_EQ(bytes("0"), bytes("4")) << name;
    EXPECT_EQ(bytes("0b"), bytes("4b")) << name;
    EXPECT_EQ(bytes("0"), bytes("5")) << name;
    EXPECT_EQ(bytes("0b"), bytes("5b")) << name;
    EXPECT_NE(bytes("0"), bytes("0b")) << "compression levels 1 and 9 differ";
  }
}

// ---------------------------------------------------------------------------------------------
// Contact sheet and text

TEST(RenderContactSheet, FramesAreSampledEvenlyWithBothEnds) {
  EXPECT_EQ(contact_sheet_frames(0, 10, 4), (std::vector<int>{0, 3, 6, 9}));
  EXPECT_EQ(contact_sheet_frames(30, 31, 4), (std::vector<int>{30, 40, 50, 60}));
  EXPECT_EQ(contact_sheet_frames(5, 3, 16), (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(contact_sheet_frames(0, 100, 1), (std::vector<int>{0}));
  EXPECT_THROW((void)contact_sheet_frames(0, 0, 4), std::invalid_argument);
}

TEST(RenderContactSheet, ThumbnailsLandInTheirCells) {
  const test::TempDir dir("sheet");
  const fs::path path = dir.path() / "s.png";
  ContactSheetLayout layout;
  layout.columns = 3;
  layout.rows = 2;
  layout.thumb_width = 40;
  layout.gap = 2;
  auto sink = make_contact_sheet(path, 80, 40, {0, 2, 4, 6, 8}, layout);
  for (int i = 0; i < 10; ++i) {
    Image f(80, 40);
    for (std::size_t k = 0; k < f.rgba.size(); k += 4) {
      f.rgba[k] = std::uint8_t(i * 25);
      f.rgba[k + 3] = 255;
    }
    sink->write(f, i);
  }
  EXPECT_FALSE(fs::exists(path));
  sink->finish();
  const Image sheet = read_image(path);
  EXPECT_EQ(sheet.width, 3 * 42 + 2);
  EXPECT_EQ(sheet.height, 2 * 22 + 2);
  // Bottom-right pixel of each thumbnail (away from the label): red = 25 x frame number.
  const int frames[] = {0, 2, 4, 6, 8};
  for (int cell = 0; cell < 5; ++cell) {
    const int x = 2 + (cell % 3) * 42 + 39;
    const int y = 2 + (cell / 3) * 22 + 19;
    EXPECT_EQ(sheet.pixel(x, y)[0], std::uint8_t(frames[cell] * 25)) << cell;
  }
  // The sixth cell never got a frame: it stays the dark background.
  EXPECT_EQ(sheet.pixel(2 + 2 * 42 + 39, 2 + 22 + 19)[0], 24);
}

TEST(RenderText, DrawsInsideItsExtentOnly) {
  Image img(120, 40);
  std::fill(img.rgba.begin(), img.rgba.end(), std::uint8_t(100));
  TextStyle style;
  style.scale = 2;
  style.background = {0, 0, 0, 255};
  const TextExtent e = measure_text("F 12", style);
  EXPECT_EQ(e.width, (4 * 6 + 1) * 2);
  EXPECT_EQ(e.height, (8 + 1) * 2);
  draw_text(img, 3, 4, "F 12", style);
  int white = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const bool inside = x >= 3 && x < 3 + e.width && y >= 4 && y < 4 + e.height;
      const std::uint8_t v = img.pixel(x, y)[0];
      if (!inside) {
        EXPECT_EQ(v, 100) << x << "," << y;
      } else {
        EXPECT_TRUE(v == 0 || v == 255) << x << "," << y;
      }
      white += v == 255 ? 1 : 0;
    }
  }
  // 'F' has 5+1+3+1+1+1+1 = 13 lit font pixels, each 2x2 image pixels; the glyphs differ.
  EXPECT_GT(white, 13 * 4);
  Image a(60, 20), b(60, 20);
  draw_text(a, 0, 0, "0", style);
  draw_text(b, 0, 0, "8", style);
  EXPECT_NE(a.rgba, b.rgba);
  Image lower(60, 20), upper(60, 20);
  draw_text(lower, 0, 0, "abc", style);
  draw_text(upper, 0, 0, "ABC", style);
  EXPECT_EQ(lower.rgba, upper.rgba);
}

}  // namespace
}  // namespace simreel::render
