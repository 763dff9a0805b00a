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

/// Encodes with libpng: zlib at `level`, and for levels below 6 one fixed row filter (Up)
/// instead of libpng's per-row trial of all five, which costs more than the deflate itself.
/// Returns an empty string on success, else the reason.
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
  png_init_io(png, file);
  png_set_compression_level(png, level);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, level < 6 ? PNG_FILTER_UP : PNG_ALL_FILTERS);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGBA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
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
  // Area weights in units of 1/(dst) source pixels, as in the hashes: exact integers.
  auto weights = [](int src, int dst) {
    auto w = std::vector<std::vector<std::pair<int, std::uint32_t>>>(static_cast<std::size_t>(dst));
    for (int i = 0; i < dst; ++i) {
      const std::int64_t a = std::int64_t(i) * src;
      const std::int64_t b = std::int64_t(i + 1) * src;
      for (int j = int(a / dst); j < src && std::int64_t(j) * dst < b; ++j) {
        const std::int64_t overlap =
            std::min(b, std::int64_t(j + 1) * dst) - std::max(a, std::int64_t(j) * dst);
        if (overlap > 0) w[std::size_t(i)].emplace_back(j, std::uint32_t(overlap));
      }
    }
    return w;
  };
  const auto wx = weights(image.width, width);
  const auto wy = weights(image.height, height);
  std::vector<std::uint64_t> rows(std::size_t(image.height) * std::size_t(width) * 4, 0);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint64_t* out = &rows[(std::size_t(y) * width + x) * 4];
      for (const auto& [j, w] : wx[std::size_t(x)]) {
        const std::uint8_t* p = image.pixel(j, y);
        for (int c = 0; c < 4; ++c) out[c] += std::uint64_t(w) * p[c];
      }
    }
  }
  Image result(width, height);
  const std::uint64_t area = std::uint64_t(image.width) * std::uint64_t(image.height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint64_t sum[4] = {0, 0, 0, 0};
      for (const auto& [j, w] : wy[std::size_t(y)]) {
        const std::uint64_t* r = &rows[(std::size_t(j) * width + x) * 4];
        for (int c = 0; c < 4; ++c) sum[c] += std::uint64_t(w) * r[c];
      }
      std::uint8_t* p = result.pixel(x, y);
      for (int c = 0; c < 4; ++c) p[c] = std::uint8_t((sum[c] + area / 2) / area);
    }
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
