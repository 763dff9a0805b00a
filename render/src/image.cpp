#include "simreel/render/image.hpp"

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

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
  // stb keeps the level in a global; the program writes frames from one thread.
  stbi_write_png_compression_level = std::clamp(compression, 0, 9);
  errno = 0;
  const int ok = stbi_write_png(tmp.c_str(), image.width, image.height, 4, image.rgba.data(),
                                image.width * 4);
  const int err = errno;
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

}  // namespace simreel::render
