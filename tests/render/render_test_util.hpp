#pragma once
// Helpers shared by the render tests: a small scene, pixel masks and temporary directories.

#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include "simreel/render/image.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render::test {

inline constexpr int kWidth = 160;
inline constexpr int kHeight = 120;

/// Camera on -y looking along +y at the origin, z up: world +x is image right, +z image up.
inline Camera front_camera() {
  Camera c;
  c.position = Vec3f(0.f, -10.f, 0.f);
  c.target = Vec3f(0.f, 0.f, 0.f);
  c.up = Vec3f(0.f, 0.f, 1.f);
  c.fov_deg = 40.f;
  return c;
}

inline RenderSettings small_settings() {
  RenderSettings s;
  s.width = kWidth;
  s.height = kHeight;
  return s;
}

/// The default-camera showcase: a plane, a box and a few particles (a regression scene).
inline void build_small_scene(Renderer& r) {
  r.add_plane(1, PlaneDesc{});
  r.add_box(2, BoxDesc{});
  r.set_transform(2, Vec3f(0.f, 0.f, 0.5f), Mat3f::Identity());
  static const float pos[] = {1.f, -1.f, 1.5f, -0.5f, 0.5f, 2.f, 0.5f, 0.5f, 1.2f};
  static const float col[] = {0.9f, 0.2f, 0.1f, 1.f, 0.1f, 0.5f, 0.9f, 1.f, 0.2f, 0.8f, 0.3f, 0.8f};
  static const float rad[] = {0.2f, 0.25f, 0.15f};
  r.set_particles(3, ParticleBatch{3, pos, col, rad, ParticleStyle::soft});
}

/// Orange-ish box pixels against the blue sky: red clearly above blue.
inline bool is_warm(const std::uint8_t* p) { return int(p[0]) > int(p[2]) + 40; }

/// Centroid of pixels satisfying `pred`; count 0 when none do.
struct Blob {
  int count = 0;
  double x = 0.0;
  double y = 0.0;
};
template <class Pred>
Blob find_blob(const Image& img, Pred pred) {
  Blob b;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      if (pred(img.pixel(x, y))) {
        ++b.count;
        b.x += x;
        b.y += y;
      }
    }
  }
  if (b.count > 0) {
    b.x /= b.count;
    b.y /= b.count;
  }
  return b;
}

/// A fresh empty directory, removed with everything in it on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    path_ = std::filesystem::temp_directory_path() /
            ("simreel-render-" + tag + "-" + std::to_string(long(::getpid())));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] int entries() const {
    int n = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(path_)) ++n;
    return n;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace simreel::render::test
