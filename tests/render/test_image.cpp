// PNG output is exact and atomic; failures name the file and leave nothing behind.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "render_test_util.hpp"
#include "simreel/render/image.hpp"

namespace simreel::render {
namespace {

namespace fs = std::filesystem;

Image pattern(int w, int h) {
  Image img(w, h);
  unsigned state = 12345u;
  for (auto& byte : img.rgba) {
    state = state * 1103515245u + 12345u;
    byte = std::uint8_t(state >> 16);
  }
  return img;
}

bool has_temp_files(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return true;
  }
  return false;
}

TEST(RenderImage, PngRoundTripsBytesExactly) {
  const test::TempDir dir("png");
  for (const int level : {0, 4, 9}) {
    const Image img = pattern(37, 23);  // odd sizes, random alpha too
    const fs::path path = dir.path() / ("img" + std::to_string(level) + ".png");
    write_png(path, img, level);
    const Image back = read_image(path);
    ASSERT_EQ(back.width, img.width);
    ASSERT_EQ(back.height, img.height);
    EXPECT_EQ(back.rgba, img.rgba) << "level " << level;
  }
  EXPECT_FALSE(has_temp_files(dir.path()));
}

// The colour type byte of a PNG file's IHDR (offset 25): 2 = RGB, 6 = RGBA.
int png_colour_type(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char header[26] = {};
  in.read(header, sizeof header);
  return in ? static_cast<unsigned char>(header[25]) : -1;
}

TEST(RenderImage, OpaqueImagesAreWrittenWithoutAlphaAndReadBackTheSame) {
  const test::TempDir dir("png-rgb");
  Image img = pattern(37, 23);
  for (std::size_t i = 3; i < img.rgba.size(); i += 4) img.rgba[i] = 255;
  for (const int level : {1, 9}) {
    const fs::path path = dir.path() / ("opaque" + std::to_string(level) + ".png");
    write_png(path, img, level);
    EXPECT_EQ(png_colour_type(path), 2) << "level " << level;
    EXPECT_EQ(read_image(path).rgba, img.rgba) << "level " << level;
  }
  // One pixel short of opaque, at the very end: the alpha channel is kept.
  img.rgba.back() = 254;
  const fs::path path = dir.path() / "last_pixel.png";
  write_png(path, img, 1);
  EXPECT_EQ(png_colour_type(path), 6);
  EXPECT_EQ(read_image(path).rgba, img.rgba);
}

// Smooth ramps with some noise: from level 6 each row takes the filter that predicts it best
// (Sub, Up, Average or Paeth, PNG specification 9.2), so every filter is decoded back here.
TEST(RenderImage, PngRowFiltersRoundTripSmoothImages) {
  const test::TempDir dir("png-filters");
  for (const bool opaque : {true, false}) {
    Image img(61, 47);
    unsigned state = 777u;
    for (int y = 0; y < img.height; ++y) {
      for (int x = 0; x < img.width; ++x) {
        state = state * 1103515245u + 12345u;
        std::uint8_t* p = img.pixel(x, y);
        p[0] = std::uint8_t(3 * x + y);
        p[1] = std::uint8_t(x * y / 7 + (state >> 30));
        p[2] = std::uint8_t(y % 13 == 0 ? state >> 24 : 4 * y);
        p[3] = opaque ? 255 : std::uint8_t(255 - x);
      }
    }
    for (const int level : {1, 6, 9}) {
      const fs::path path = dir.path() / ("ramp" + std::to_string(level) + (opaque ? "o" : "a") + ".png");
      write_png(path, img, level);
      EXPECT_EQ(read_image(path).rgba, img.rgba) << "level " << level << (opaque ? " opaque" : " with alpha");
    }
  }
}

TEST(RenderImage, WritePngReplacesAnExistingFile) {
  const test::TempDir dir("png-replace");
  const fs::path path = dir.path() / "a.png";
  write_png(path, pattern(4, 4));
  const Image second = pattern(8, 2);
  write_png(path, second);
  EXPECT_EQ(read_image(path).rgba, second.rgba);
  EXPECT_EQ(dir.entries(), 1);
}

TEST(RenderImage, WritingIntoAnUncreatableDirectoryNamesThePath) {
  // Missing directories are created (AtomicFile); one that cannot be, under a regular file,
  // fails with the path and leaves nothing.
  const test::TempDir dir("png-missing");
  write_png(dir.path() / "new" / "dir" / "frame.png", pattern(4, 4));
  EXPECT_TRUE(fs::exists(dir.path() / "new" / "dir" / "frame.png"));
  std::ofstream(dir.path() / "no") << "a file";
  const fs::path path = dir.path() / "no" / "such" / "frame.png";
  try {
    write_png(path, pattern(4, 4));
    FAIL() << "write_png succeeded into a directory that cannot exist";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "no"));
  EXPECT_EQ(dir.entries(), 2);
}

TEST(RenderImage, FailedRenameLeavesNoTemporaryFile) {
  // The target is a non-empty directory: encoding succeeds, the final rename cannot.
  const test::TempDir dir("png-rename");
  const fs::path target = dir.path() / "frame.png";
  fs::create_directories(target / "child");
  EXPECT_THROW(write_png(target, pattern(4, 4)), IoError);
  EXPECT_FALSE(has_temp_files(dir.path()));
  EXPECT_EQ(dir.entries(), 1);
}

TEST(RenderImage, ReadErrorsNameThePath) {
  const test::TempDir dir("png-read");
  const fs::path missing = dir.path() / "missing.png";
  try {
    (void)read_image(missing);
    FAIL() << "read_image succeeded on a missing file";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
  const fs::path junk = dir.path() / "junk.png";
  std::ofstream(junk) << "not an image";
  EXPECT_THROW((void)read_image(junk), IoError);
}

/// The message read_image gives for `path`, "" if it reads.
std::string read_error(const fs::path& path) {
  try {
    (void)read_image(path);
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

/// The bytes of the file at `path`.
std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// A 4 x 1 PNG whose IHDR chunk is rewritten to declare w x h pixels, its CRC-32 recomputed so
/// that only the size is wrong.
void write_declared_png(const fs::path& path, std::uint32_t w, std::uint32_t h) {
  write_png(path, pattern(4, 1));
  std::string bytes = file_bytes(path);
  ASSERT_EQ(bytes.substr(12, 4), "IHDR");
  for (int k = 0; k < 4; ++k) {
    bytes[std::size_t(16 + k)] = char(w >> (24 - 8 * k));
    bytes[std::size_t(20 + k)] = char(h >> (24 - 8 * k));
  }
  std::uint32_t crc = 0xffffffffu;  // over the chunk's type and data
  for (std::size_t i = 12; i < 12 + 4 + 13; ++i) {
    crc ^= std::uint8_t(bytes[i]);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  crc = ~crc;
  for (int k = 0; k < 4; ++k) bytes[29 + std::size_t(k)] = char(crc >> (24 - 8 * k));
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(RenderImage, EmptyOversizedAndNonRegularImagesAreRefusedByName) {
  const test::TempDir dir("png-limits");
  // stb_image reads a PNM header with no digits as a 0 x 0 image and returned it: `simreel hash`
  // then failed with exit 1 and "cannot hash an empty or malformed image", naming no file.
  const fs::path empty = dir.path() / "empty.png";
  std::ofstream(empty, std::ios::binary) << "P6\n\x9d\xe3\xfeWJ";
  std::string err = read_error(empty);
  EXPECT_NE(err.find(empty.string() + ": 0 x 0 pixels, expected 1 to 16384 on each side"), std::string::npos) << err;
  // A PNG whose header declares 20000 x 1 pixels: refused from the header, before decoding.
  const fs::path wide = dir.path() / "wide.png";
  write_declared_png(wide, 20000, 1);
  err = read_error(wide);
  EXPECT_NE(err.find(wide.string() + ": 20000 x 1 pixels, expected 1 to 16384 on each side"), std::string::npos) << err;
  // A FIFO would block the read (it did: a texture named /dev/stdin). Held open for writing and
  // given some bytes here, so that a regression fails this test instead of hanging it.
  const fs::path fifo = dir.path() / "pipe.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int writer = ::open(fifo.c_str(), O_RDWR | O_NONBLOCK);
  ASSERT_GE(writer, 0);
  const std::string junk(4096, 'x');
  ASSERT_EQ(::write(writer, junk.data(), junk.size()), ssize_t(junk.size()));
  err = read_error(fifo);
  ::close(writer);
  EXPECT_NE(err.find(fifo.string() + ": not a regular file"), std::string::npos) << err;
  // A PNG cut short: in its pixels, between chunks, inside a chunk's type (stb_image's reason
  // was then a fragment of it: "(stb_image: ID)") or length, a few bytes into the compressed
  // rows (its reason was empty: "(stb_image: )"), and inside the closing IEND chunk.
  const fs::path whole = dir.path() / "whole.png";
  write_png(whole, pattern(64, 64));
  const std::string bytes = file_bytes(whole);
  const std::size_t idat = bytes.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  for (const std::size_t size : {bytes.size() / 2, idat - 4, idat - 2, idat + 2, idat + 10, bytes.size() - 6}) {
    const fs::path cut = dir.path() / ("cut" + std::to_string(size) + ".png");
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, size);
    err = read_error(cut);
    EXPECT_NE(err.find(cut.string() + ": a PNG file cut short: its data ends early"), std::string::npos) << err;
    EXPECT_EQ(err.find("stb_image"), std::string::npos) << err;
  }
}

TEST(RenderImage, RefusedImagesSayWhatIsWrongNotUnknownType) {
  // stb_image tries each format in turn and reports the last one's reason, so each of these
  // PNGs read "unknown image type", as if PNG were not read at all.
  const test::TempDir dir("png-reasons");
  // 20000 x 20000 RGBA is 1.6 GB of pixels: stb_image refuses it before reporting a size.
  const fs::path big = dir.path() / "big.png";
  write_declared_png(big, 20000, 20000);
  std::string err = read_error(big);
  EXPECT_NE(err.find(big.string() + ": 20000 x 20000 pixels, expected 1 to 16384 on each side"), std::string::npos)
      << err;
  // A PNG's first 20 bytes: the signature, but not the whole header.
  const fs::path head = dir.path() / "head.png";
  write_png(head, pattern(8, 8));
  fs::resize_file(head, 20);
  err = read_error(head);
  EXPECT_NE(err.find(head.string() + ": a PNG file whose header is cut short or corrupt"), std::string::npos) << err;
  // Its compressed data damaged: stb_image's reason, named as its own.
  const fs::path damaged = dir.path() / "damaged.png";
  write_png(damaged, pattern(8, 8));
  std::string bytes = file_bytes(damaged);
  const std::size_t idat = bytes.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  bytes[idat + 4] = char(bytes[idat + 4] ^ 0xff);  // the zlib header's first byte
  std::ofstream(damaged, std::ios::binary | std::ios::trunc) << bytes;
  err = read_error(damaged);
  EXPECT_NE(err.find(damaged.string() + ": a PNG file that cannot be decoded (stb_image: "), std::string::npos)
      << err;
  // No signature stb_image knows (and not a TGA): the formats that are read.
  const fs::path text = dir.path() / "notes.png";
  std::ofstream(text) << "not an image at all, just some words in a file";
  err = read_error(text);
  EXPECT_NE(err.find(text.string() + ": not an image format simreel reads (PNG, JPEG, "), std::string::npos) << err;
  EXPECT_EQ(err.find("unknown image type"), std::string::npos) << err;
}

}  // namespace
}  // namespace simreel::render
