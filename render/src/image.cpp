#include "simreel/render/image.hpp"

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <string>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include <unistd.h>

namespace simreel::render {

namespace fs = std::filesystem;

void write_png(const fs::path& path, const Image& image, int compression) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw IoError("cannot write " + path.string() + ": image is empty or its size does not match");
  }
  // Same directory as the target, so the final rename cannot cross file systems; a dot name so
  // a half-written file never looks like a frame.
  std::string tmp_name = ".";  // built piecewise: GCC 12 warns falsely on "." + string&&
  tmp_name += path.filename().string();
  tmp_name += ".tmp-";
  tmp_name += std::to_string(static_cast<long>(::getpid()));
  const fs::path tmp = path.parent_path() / tmp_name;
  // stb keeps the level in a global, and several writer threads may encode PNGs at once (a
  // sequence, a contact sheet, a golden's thumbnails); holding the lock over the whole encode
  // keeps each file's bytes independent of timing.
  static std::mutex stb_level_mutex;
  int ok = 0;
  int err = 0;
  {
    const std::lock_guard lock(stb_level_mutex);
    stbi_write_png_compression_level = std::clamp(compression, 0, 9);
    errno = 0;
    ok = stbi_write_png(tmp.c_str(), image.width, image.height, 4, image.rgba.data(),
                        image.width * 4);
    err = errno;
  }
  std::error_code ec;
  if (ok == 0) {
    fs::remove(tmp, ec);
    throw IoError("cannot write " + path.string() + ": " +
                  (err != 0 ? std::strerror(err) : "PNG encoding failed"));
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw IoError("cannot write " + path.string() + ": " + ec.message());
  }
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
