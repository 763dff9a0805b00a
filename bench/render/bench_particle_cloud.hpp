#pragma once
// The particle cloud both render benchmarks draw: plain arrays, no simreel types, so the raw
// OSMesa baseline can include it too. A fountain-like column of n soft droplets in front of
// the default camera, fixed pseudo-random layout.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace bench {

struct ParticleCloud {
  std::vector<float> position;  // (n x 3) m
  std::vector<float> color;     // (n x 4) linear RGBA
  std::vector<float> radius;    // (n) m
};

inline ParticleCloud make_particle_cloud(std::size_t n) {
  ParticleCloud c;
  c.position.resize(3 * n);
  c.color.resize(4 * n);
  c.radius.resize(n);
  std::uint32_t state = 2463534242u;
  auto next = [&state] {  // xorshift32 in [0, 1)
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return float(state >> 8) / float(1u << 24);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const float h = next();
    const float spread = 0.15f + 0.9f * h;
    c.position[3 * i] = spread * (2.f * next() - 1.f);
    c.position[3 * i + 1] = spread * (2.f * next() - 1.f);
    c.position[3 * i + 2] = 0.1f + 2.6f * h;
    c.color[4 * i] = 0.35f + 0.2f * next();
    c.color[4 * i + 1] = 0.6f + 0.2f * next();
    c.color[4 * i + 2] = 0.95f;
    c.color[4 * i + 3] = 0.8f;
    c.radius[i] = 0.008f + 0.01f * next();
  }
  return c;
}

}  // namespace bench
