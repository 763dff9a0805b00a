// simreel's renderer on the particle frame of raw_osmesa_baseline (100k soft sprites,
// 1280x720, 4x MSAA, read back every frame), as a ratio of the baseline's frame time, plus
// variants that show where the time goes. Usage: bench_render [particles] [frames] [only cases naming this]
// Runs ./raw_osmesa_baseline from its own directory for the reference figure.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "bench_particle_cloud.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/renderer.hpp"

namespace {

using namespace simreel::render;

// Process CPU time (all threads, llvmpipe's included) per frame: on a machine shared with
// other jobs it varies much less than wall time. Median of `frames` after 2 warm-up frames;
// the median wall time of the same frames goes to `wall_ms`.
double median_ms(int frames, const std::function<void()>& frame, double* wall_ms = nullptr) {
  std::vector<double> ms, wall;
  for (int f = 0; f < frames + 2; ++f) {
    const auto w0 = std::chrono::steady_clock::now();
    const std::clock_t t0 = std::clock();
    frame();
    const std::clock_t t1 = std::clock();
    const auto w1 = std::chrono::steady_clock::now();
    if (f >= 2) {
      ms.push_back(1000.0 * double(t1 - t0) / CLOCKS_PER_SEC);
      wall.push_back(std::chrono::duration<double, std::milli>(w1 - w0).count());
    }
  }
  std::sort(ms.begin(), ms.end());
  std::sort(wall.begin(), wall.end());
  if (wall_ms != nullptr) *wall_ms = wall[wall.size() / 2];
  return ms[ms.size() / 2];
}

struct Case {
  const char* name;
  int msaa;
  ParticleStyle style;
  std::size_t particles;
  bool particle_shadows;
  ParticleTexture texture = ParticleTexture::none;
  float bloom = Bloom{}.intensity;  // the default look: bloom on
  float shutter_deg = 0.f;          // > 0: a box moves every frame, blurred by the shutter
  float radius_scale = 1.f;         // > 1: big puffs (smoke): overdraw instead of many small sprites
};

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::size_t(std::atol(argv[1])) : 100000;
  const int frames = argc > 2 ? std::atoi(argv[2]) : 20;
  const char* only = argc > 3 ? argv[3] : nullptr;  // run only the cases whose name contains this
  const bench::ParticleCloud cloud = bench::make_particle_cloud(n);
  const auto context = create_context(Backend::osmesa);

  double full = 0.0;
  for (const Case& c : {Case{"soft, msaa 4 (the baseline's frame)", 4, ParticleStyle::soft, n, false},
                        Case{"soft, msaa 4, bloom off", 4, ParticleStyle::soft, n, false, ParticleTexture::none, 0.f},
                        Case{"soft, msaa 0", 0, ParticleStyle::soft, n, false},
                        Case{"additive (no sort), msaa 4", 4, ParticleStyle::additive, n, false},
                        Case{"droplet (opaque), msaa 4", 4, ParticleStyle::droplet, n, false},
                        Case{"soft + particle shadows, msaa 4", 4, ParticleStyle::soft, n, true},
                         Case{"soft, smoke texture, msaa 4", 4, ParticleStyle::soft, n, false, ParticleTexture::smoke},
                         Case{"additive, flame texture, msaa 4", 4, ParticleStyle::additive, n, false, ParticleTexture::flame},
                         Case{"empty frame (sky, tone map, read back), msaa 4", 4, ParticleStyle::soft, 0, false},
                         Case{"empty frame, bloom off", 4, ParticleStyle::soft, 0, false, ParticleTexture::none, 0.f},
                         Case{"soft + moving box, shutter 0", 4, ParticleStyle::soft, n, false, ParticleTexture::none,
                              Bloom{}.intensity, 0.f},
                         Case{"soft + moving box, shutter 180 (8 samples)", 4, ParticleStyle::soft, n, false,
                              ParticleTexture::none, Bloom{}.intensity, 180.f},
                         Case{"big smoke puffs (n/50, radius x20, ~30 px), msaa 4", 4, ParticleStyle::soft, n / 50, false,
                              ParticleTexture::smoke, Bloom{}.intensity, 0.f, 20.f}}) {
    if (only != nullptr && std::strstr(c.name, only) == nullptr) continue;
    RenderSettings s;
    s.width = 1280;
    s.height = 720;
    s.msaa_samples = c.msaa;
    s.particle_shadows = c.particle_shadows;
    s.bloom.intensity = c.bloom;
    s.shutter_deg = c.shutter_deg;
    Renderer r(*context, s);
    const bool box = std::strstr(c.name, "moving box") != nullptr;
    if (box) r.add_box(2, BoxDesc{});
    int frame = 0;
    std::vector<float> radius = cloud.radius;
    for (float& r : radius) r *= c.radius_scale;
    ParticleBatch batch{c.particles, cloud.position.data(), cloud.color.data(), radius.data(), c.style};
    batch.texture = c.texture;
    double wall = 0.0;
    const double ms = median_ms(frames, [&] {
      r.set_particles(1, batch);  // new data every frame, as from a simulation
      if (box) r.set_transform(2, Vec3f(0.2f * float(frame++ % 10) - 1.f, 0.f, 0.5f), Mat3f::Identity());
      (void)r.render();
    }, &wall);
    if (full == 0.0) full = ms;
    std::printf("simreel %-48s %8.2f ms CPU/frame %8.2f ms wall\n", c.name, ms, wall);
  }
  if (only == nullptr || std::strstr("64x36", only) != nullptr) {
    RenderSettings s;
    s.width = 64;
    s.height = 36;
    Renderer r(*context, s);
    const ParticleBatch batch{n, cloud.position.data(), cloud.color.data(), cloud.radius.data(), ParticleStyle::soft};
    const double copy = median_ms(frames, [&] { r.set_particles(1, batch); });
    double wall = 0.0;
    const double tiny = median_ms(frames, [&] {
      r.set_particles(1, batch);
      (void)r.render();
    }, &wall);
    std::printf("simreel %-48s %8.2f ms CPU/frame\n", "set_particles copy only", copy);
    std::printf("simreel %-48s %8.2f ms CPU/frame %8.2f ms wall\n",
                "soft at 64x36 (CPU sort + upload + vertices)", tiny, wall);
  }

  const std::filesystem::path self = std::filesystem::absolute(argv[0]).parent_path();
  const std::string cmd = (self / "raw_osmesa_baseline").string() + " " + std::to_string(n) + " " +
                          std::to_string(frames) + " 4";
  std::FILE* p = popen(cmd.c_str(), "r");
  char line[512] = {};
  double base = 0.0;
  if (p != nullptr && std::fgets(line, sizeof line, p) != nullptr) {
    std::fputs(line, stdout);
    if (const char* m = std::strstr(line, "median ")) base = std::atof(m + 7);
  }
  if (p != nullptr) pclose(p);
  if (base > 0.0 && only == nullptr) std::printf("ratio simreel / raw baseline: %.2f\n", full / base);
  return 0;
}
