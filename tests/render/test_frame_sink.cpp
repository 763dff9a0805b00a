// Frame sinks: PNG sequences, MP4/GIF through ffmpeg, and no partial files on failure or abort.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include <sys/stat.h>

#include "render_test_util.hpp"
#include "simreel/render/frame_sink.hpp"
#include "simreel/render/image.hpp"

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
  auto sink = make_video(path, 161, 121, VideoOptions{10.0, 23});
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

}  // namespace
}  // namespace simreel::render
