#pragma once
// Private: the per-particle look computed on the CPU when a batch is copied (set_particles):
// each particle's own random number, and the flame's temperature ramp with its flicker.
// Deterministic: a function of the particle's id and age alone, never of the frame or thread.

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace simreel::render::detail {

/// A number in [0, 1) fixed for the particle's whole life: splitmix64 of its stable id.
inline float particle_random(std::uint64_t id) {
  std::uint64_t z = id + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return float(z >> 40) * (1.f / 16777216.f);
}

/// Linear RGB of a flame at `age01` = age / lifetime (hot at birth, cooling as it rises):
/// a blackbody-like ramp (Planck's colours of ~2000 K down to ~900 K, brightest first:
/// white-yellow core -> orange -> red -> a dim ember), times a flicker made of two incommensurate
/// sines of the particle's age with its own phase, so neighbouring flames never pulse together
/// and no frame pops. Writes rgb to `rgb[0..2]` (alpha is left alone).
inline void flame_color(float age01, float age_s, float rnd, float* rgb) {
  struct Key {
    float t, r, g, b;
  };
  // Brightness above 1 at the core: the bloom pass makes it glow.
  static constexpr Key kRamp[] = {{0.00f, 1.60f, 1.30f, 0.75f}, {0.18f, 1.30f, 0.78f, 0.22f},
                                  {0.45f, 0.95f, 0.34f, 0.05f}, {0.75f, 0.45f, 0.08f, 0.01f},
                                  {1.00f, 0.08f, 0.012f, 0.002f}};
  const float t = std::clamp(age01, 0.f, 1.f);
  int k = 0;
  while (k < 3 && t > kRamp[k + 1].t) ++k;
  const Key& a = kRamp[k];
  const Key& b = kRamp[k + 1];
  const float f = (t - a.t) / (b.t - a.t);
  const float phase = 6.2831853f * rnd;
  const float flicker = 0.82f + 0.18f * std::sin(29.f * age_s + phase) * std::sin(17.3f * age_s + 2.f * phase);
  rgb[0] = (a.r + f * (b.r - a.r)) * flicker;
  rgb[1] = (a.g + f * (b.g - a.g)) * flicker;
  rgb[2] = (a.b + f * (b.b - a.b)) * flicker;
}

/// On/off strobe (glitter, fireworks crackle): 1 while the particle's flash is lit, 0 between
/// flashes. Lit while fract(age_s * hz + rnd) < duty, so each particle keeps its own phase and
/// neighbours pop at different instants; a function of age and id alone (the same bytes on every
/// render). hz <= 0: always lit.
inline float strobe(float age_s, float rnd, float hz, float duty) {
  if (!(hz > 0.f)) return 1.f;
  const float x = age_s * hz + rnd;
  return x - std::floor(x) < duty ? 1.f : 0.f;
}

}  // namespace simreel::render::detail
