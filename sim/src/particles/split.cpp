// Particle split (Coutinho §3.9.1), see SplitDef for the nine parameters' meanings.
#include "particles/split.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "simreel/sim/ranges.hpp"

namespace simreel::sim::detail {

std::size_t split_particles(const EmitterDef& def, Rng& rng, ParticleStore& s, std::size_t end,
                            std::uint64_t& next_id) {
  const SplitDef& sp = def.split;
  if (!sp.enabled) return 0;
  constexpr double kPi = std::numbers::pi;
  constexpr float kMinMass = float(ranges::kParticleMassMin);
  const double cos_max = std::cos(sp.direction_deviation_deg * (kPi / 180.0));
  const float f = float(sp.size_fraction);
  const float mass_factor = f * f * f;  // same density
  std::size_t created = 0;
  for (std::size_t i = 0; i < end; ++i) {
    if (!(s.age[i] < s.lifetime[i])) continue;  // died this step
    if (s.split_generation[i] >= sp.depth) continue;
    if (s.age[i] < float(sp.age)) continue;
    // split_countdown: steps left before the next split (0 = due now). It runs down only once
    // the split age is reached, so a child younger than the split age waits for it first.
    if (s.split_countdown[i] > 0) --s.split_countdown[i];
    if (s.split_countdown[i] > 0) continue;
    if (s.count + sp.children > def.max_particles) continue;  // wait for room

    const Vec3 v(s.velocity[3 * i], s.velocity[3 * i + 1], s.velocity[3 * i + 2]);
    const double speed = v.norm();
    const Vec3 axis = speed > 0.0 ? Vec3(v / speed) : Vec3::UnitZ();
    const Quat to_axis = Quat::FromTwoVectors(Vec3::UnitZ(), axis);
    const double child_speed = sp.velocity_fraction * speed;
    const std::uint8_t generation = std::uint8_t(s.split_generation[i] + 1);
    const std::size_t first = s.append(sp.children);
    for (std::size_t c = 0; c < sp.children; ++c) {
      const std::size_t j = first + c;
      // Uniform over the cap of half-angle direction_deviation_deg: cos(theta) uniform.
      const double cos_t = 1.0 - rng.uniform() * (1.0 - cos_max);
      const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
      const double phi = 2.0 * kPi * rng.uniform();
      const Vec3 d = to_axis * Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
      const double age =
          double(s.age[i]) +
          (sp.lifetime_deviation > 0.0 ? rng.uniform(-sp.lifetime_deviation, sp.lifetime_deviation) : 0.0);
      for (std::size_t k = 0; k < 3; ++k) {
        s.position[3 * j + k] = s.position[3 * i + k];
        if (s.track_prev) s.prev_position[3 * j + k] = s.position[3 * i + k];
        s.velocity[3 * j + k] = float(child_speed * d[Eigen::Index(k)]);
      }
      for (std::size_t k = 0; k < 4; ++k) s.color[4 * j + k] = s.color[4 * i + k];
      s.radius[j] = f * s.radius[i];
      s.base_radius[j] = f * s.base_radius[i];
      s.mass[j] = std::max(kMinMass, s.mass[i] * mass_factor);
      s.lifetime[j] = s.lifetime[i];
      s.age[j] = std::clamp(float(age), 0.0f, s.lifetime[i]);
      s.tint[j] = s.tint[i];
      s.id[j] = next_id++;
      s.split_generation[j] = generation;
      s.split_countdown[j] = std::uint32_t(sp.delay_steps);
      s.from_split[j] = 1;
    }
    s.split_generation[i] = generation;
    s.split_countdown[i] = std::uint32_t(sp.delay_steps);
    created += sp.children;
  }
  return created;
}

}  // namespace simreel::sim::detail
