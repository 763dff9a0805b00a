#pragma once
/// @file types.hpp
/// Conventions (see README "Conventions"): SI units (m, kg, s), right-handed, z up, angles in
/// radians inside the engine. Vectors are in the world frame unless a name says otherwise.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace simreel::sim {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// A parameter given as mean + deviation and drawn from a normal distribution
/// N(mean, deviation²) for every particle (Coutinho §3.8: "for each parameter, we define its
/// mean value and deviation"). Draws are clamped to [min, max].
/// With `uniform` set, a draw is instead uniform on [min, max) (mean (min + max) / 2, variance
/// (max - min)² / 12); mean and deviation are then ignored and min, max must be finite.
struct Distribution {
  double mean = 0.0;
  double deviation = 0.0;  ///< standard deviation, same unit as mean, >= 0
  double min = -1e300;     ///< lower clamp of a draw (lower end when `uniform`)
  double max = 1e300;      ///< upper clamp of a draw (upper end when `uniform`)
  bool uniform = false;    ///< draw uniformly on [min, max) instead of N(mean, deviation²)
};

/// What happens to a particle when it hits a collider (the response is always computed first).
enum class HitAction {
  bounce,  ///< impulse with restitution and friction (Coutinho §3.6.1); the default
  stick,   ///< the particle stops on the surface (e = 0, unlimited friction) and then rests there
           ///< like any resting contact (§3.6.3): it stays while the contact holds it
  kill,    ///< the particle is removed at the end of the step
  split,   ///< the particle is removed and `SplitOnHit::count` droplets are spawned at the hit
           ///< point into the same system (the rain-splash hook of §3.9.1)
};

/// Droplets spawned by HitAction::split. Each droplet leaves the contact point (lifted by its own
/// radius along the normal) with speed speed_fraction * |v| of the impact, in a direction drawn
/// uniformly in the cone of half-angle spread_deg around the surface normal; its radius and mass
/// are the parent's times size_fraction and size_fraction³; it lives `lifetime` seconds. Only
/// particles of radius >= min_radius split (small drops do not splash); smaller ones are removed,
/// so a splash cascade ends after a bounded number of generations.
struct SplitOnHit {
  double min_radius = 1e-3;      ///< (m) >= 0; must exceed size_fraction * the emitted radius
  int count = 4;                 ///< droplets per hit, in [0, 64]
  double speed_fraction = 0.3;   ///< of the impact speed, >= 0
  double size_fraction = 0.3;    ///< of the parent radius, in (0, 1]
  double lifetime = 0.3;         ///< (s) > 0
  double spread_deg = 60.0;      ///< cone half-angle around the normal, in [0, 90]
};

/// Surface response parameters of a collider (Coutinho §3.6.1).
struct Material {
  Material() = default;
  /// The two coefficients most scenes set ({e, mu} still reads as before the other fields).
  Material(double restitution_e, double friction_mu)
      : restitution(restitution_e), friction(friction_mu) {}

  double restitution = 0.5;  ///< coefficient of restitution e in [0, 1]: v_n' = -e v_n
  double friction = 0.3;     ///< dynamic Coulomb friction coefficient mu_d >= 0
  /// Static Coulomb coefficient mu_s >= 0 for a contact that is not sliding: it holds a particle
  /// or a body on an incline of angle theta when mu_s >= tan theta; once broken loose it slides
  /// with `friction` (Coutinho §3.6.3). Negative: equal to `friction`. Body contacts take the
  /// geometric mean of both sides' mu_s, and never less than their mixed `friction`.
  double static_friction = -1.0;
  HitAction on_hit = HitAction::bounce;
  SplitOnHit split;          ///< used when on_hit == split
  [[nodiscard]] double static_mu() const { return static_friction < 0.0 ? friction : static_friction; }
};

/// Rigid transform: x_world = rotation * x_local + translation.
struct Transform {
  Vec3 translation = Vec3::Zero();  ///< (m), world frame
  Quat rotation = Quat::Identity();
};

}  // namespace simreel::sim
