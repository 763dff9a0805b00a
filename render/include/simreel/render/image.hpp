#pragma once
/// @file image.hpp
/// RGBA8 images, rows top to bottom, and their I/O (PNG compressed with libdeflate, images read
/// with stb_image).

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace simreel::render {

/// 8-bit RGBA image, rows stored top to bottom, 4 bytes per pixel, no padding.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  ///< (height x width x 4)

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(std::size_t(w) * std::size_t(h) * 4, 0) {}
  [[nodiscard]] std::uint8_t* pixel(int x, int y) { return &rgba[(std::size_t(y) * width + x) * 4]; }
  [[nodiscard]] const std::uint8_t* pixel(int x, int y) const {
    return &rgba[(std::size_t(y) * width + x) * 4];
  }
};

/// An output or input file could not be written or read; the message names the file.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes a PNG atomically through AtomicFile (atomic_file.hpp): a temporary name in the same
/// directory, fsync, rename; the parent directory is created if missing.
/// @param compression deflate level 0–9 (libdeflate). Below 6 every row uses the Up filter;
///        from 6 each row takes the filter whose output has the least magnitude (as libpng).
///        Measured on a 1280x720 fountain frame (CPU time, 2026-11-24): level 1 17 ms, 592 KB;
///        level 4 37 ms, 530 KB; level 6 91 ms, 446 KB; level 9 0.57 s, 375 KB. The bytes
///        depend only on the image and the level. An image whose alpha is 255 everywhere is
///        written as 8-bit RGB (a quarter less to deflate), any other as RGBA.
/// @throws IoError naming the path; std::bad_alloc when memory runs out.
void write_png(const std::filesystem::path& path, const Image& image, int compression = 4);

/// The largest image side read_image accepts: 16384 px, the least GL_MAX_TEXTURE_SIZE that
/// OpenGL 4.5 guarantees, so any image read uploads as a texture (at most 1 GiB of RGBA8).
inline constexpr int kMaxImageSide = 16384;

/// Reads PNG/JPEG/BMP/TGA/PNM/... (what stb_image reads, by content) into RGBA8.
/// @throws IoError naming the path and the reason: no such file, not a regular file (a FIFO
///         would block), no image signature stb_image knows, a file of a known format cut
///         short or corrupt (with stb_image's reason), or a side of 0 or above kMaxImageSide
///         pixels (checked from the header before the pixels are decoded; for a PNG from its
///         IHDR chunk, since stb_image refuses one of over 2^30 bytes of pixels unsized).
Image read_image(const std::filesystem::path& path);

/// Area-average (box filter) resample to width x height, exact in integer arithmetic, so the
/// same input always gives the same bytes; for thumbnails (contact sheets, golden frames).
/// @throws std::invalid_argument for an empty image or a target size below 1x1.
Image resize_box(const Image& image, int width, int height);

/// Copies `src` into `dst` with its top-left corner at (x0, y0) in dst pixels; parts falling
/// outside `dst` are clipped.
void blit(Image& dst, const Image& src, int x0, int y0);

}  // namespace simreel::render
