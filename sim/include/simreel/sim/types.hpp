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

/// Surface response parameters of a collider (Coutinho §3.6.1).
struct Material {
  double restitution = 0.5;  ///< coefficient of restitution e in [0, 1]: v_n' = -e v_n
  double friction = 0.3;     ///< dynamic Coulomb friction coefficient mu >= 0
};

/// Rigid transform: x_world = rotation * x_local + translation.
struct Transform {
  Vec3 translation = Vec3::Zero();  ///< (m), world frame
  Quat rotation = Quat::Identity();
};

}  // namespace simreel::sim
