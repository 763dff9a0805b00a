#include "simreel/render/image.hpp"

#include <stb_image.h>
#include <png.h>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "box_resample.hpp"
#include "simreel/render/atomic_file.hpp"

namespace simreel::render {

namespace fs = std::filesystem;

namespace {

/// libpng reports errors through longjmp; the message is kept for the IoError.
struct PngErrorState {
  std::jmp_buf jump;
  std::string message;
};

void on_png_error(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  state->message = message != nullptr ? message : "PNG encoding failed";
  std::longjmp(state->jump, 1);
}

void on_png_warning(png_structp, png_const_charp) {}

/// True when every pixel's alpha is 255: the PNG then needs no alpha channel.
bool opaque(const Image& image) {
  const std::uint8_t* p = image.rgba.data();
  const std::size_t n = image.rgba.size();
  std::uint8_t all = 255;
  for (std::size_t i = 3; i < n; i += 4) all &= p[i];  // no early exit: the loop vectorises
  return all == 255;
}

/// Encodes with libpng: zlib at `level`, and for levels below 6 one fixed row filter (Up)
/// instead of libpng's per-row trial of all five, which costs more than the deflate itself.
/// An opaque image is written as RGB (libpng drops the filler byte): a quarter less to filter
/// and deflate, and smaller files. Returns an empty string on success, else the reason.
std::string encode_png(std::FILE* file, const Image& image, int level) {
  PngErrorState state;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, on_png_error, on_png_warning);
  if (png == nullptr) return "out of memory";
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    return "out of memory";
  }
  // Nothing with a destructor lives between setjmp and the calls that may longjmp.
  if (setjmp(state.jump) != 0) {
    png_destroy_write_struct(&png, &info);
    return state.message;
  }
  const bool rgb = opaque(image);  // after setjmp: not live across a longjmp
  png_init_io(png, file);
  png_set_compression_level(png, level);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, level < 6 ? PNG_FILTER_UP : PNG_ALL_FILTERS);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8,
               rgb ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE,
               PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
  if (rgb) png_set_filler(png, 0, PNG_FILLER_AFTER);  // rows stay RGBA in memory
  for (int y = 0; y < image.height; ++y) png_write_row(png, image.pixel(0, y));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return {};
}

}  // namespace

void write_png(const fs::path& path, const Image& image, int compression) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw IoError("cannot write " + path.string() + ": image is empty or its size does not match");
  }
  AtomicFile file(path);  // a half-written PNG never appears under the final name
  const std::string error = encode_png(file.file(), image, std::clamp(compression, 0, 9));
  if (!error.empty()) throw IoError("cannot write " + path.string() + ": " + error);  // discarded
  file.commit();
}

Image read_image(const fs::path& path) {
  int w = 0;
  int h = 0;
  int channels = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 4);
  if (data == nullptr) {
    const char* reason = stbi_failure_reason();
    throw IoError("cannot read image " + path.string() + ": " +
                  (reason != nullptr ? reason : "unknown error"));
  }
  Image image(w, h);
  std::memcpy(image.rgba.data(), data, image.rgba.size());
  stbi_image_free(data);
  return image;
}

Image resize_box(const Image& image, int width, int height) {
  if (image.width < 1 || image.height < 1 || width < 1 || height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw std::invalid_argument("resize_box: empty image or target size");
  }
  // Exact area sums (box_resample.hpp, as for the hashes), rounded to nearest once.
  const std::vector<std::int64_t> sums =
      detail::box_resample(image.rgba.data(), image.width, image.height, 4, width, height);
  Image result(width, height);
  const std::int64_t area = std::int64_t(image.width) * std::int64_t(image.height);
  for (std::size_t i = 0; i < sums.size(); ++i) {
    result.rgba[i] = std::uint8_t((sums[i] + area / 2) / area);
  }
  return result;
}

void blit(Image& dst, const Image& src, int x0, int y0) {
  for (int y = std::max(0, -y0); y < src.height && y0 + y < dst.height; ++y) {
    const int x_begin = std::max(0, -x0);
    const int x_end = std::min(src.width, dst.width - x0);
    if (x_end <= x_begin) return;
    std::memcpy(dst.pixel(x0 + x_begin, y0 + y), src.pixel(x_begin, y),
                std::size_t(x_end - x_begin) * 4);
  }
}

}  // namespace simreel::render
