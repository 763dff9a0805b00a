#pragma once
/// @file physics.hpp
/// The physical relations behind the effect knobs (Coutinho §3.9.1): from what a user can name
/// (rainfall in mm/h, drop size, apex height, rise speed) to emitter and force parameters.
/// SI units unless a name says otherwise.

namespace simreel::effects {

inline constexpr double kWaterDensity = 1000.0;  ///< (kg/m³)

/// Mass (kg) of a spherical water drop of diameter `diameter_mm` (mm): ρ_w π D³ / 6.
/// @throws std::invalid_argument unless diameter_mm > 0.
double drop_mass(double diameter_mm);

/// Terminal fall speed (m/s) of a raindrop in still air at sea level, from its diameter (mm):
/// v_t = 9.65 - 10.3 exp(-0.6 D) (Atlas, Srivastava & Sekhon 1973, fit to Gunn & Kinzer 1949;
/// within a few percent for 0.3 mm <= D <= 6 mm). @throws std::invalid_argument outside
/// [0.3, 6] mm.
double raindrop_terminal_velocity(double diameter_mm);

/// Viscous drag coefficient k_d (kg/s) that makes a particle of mass `mass` (kg) fall at
/// `terminal_speed` (m/s) under gravity `g` (m/s²): v_t = m g / k_d (Coutinho §3.3.2), so
/// k_d = m g / v_t. @throws std::invalid_argument unless all arguments are > 0.
double drag_for_terminal_velocity(double mass, double terminal_speed, double g = 9.81);

/// Quadratic drag coefficient c_2 (kg/m) of a sphere of diameter `diameter_mm` (mm) in air:
/// F = -c_2 |v| v with c_2 = ½ ρ_air C_d A, A = π r² (r = D / 2), ρ_air = `air_density` (kg/m³,
/// sea level 1.225) and C_d = `drag_coefficient` (0.47, a smooth sphere at high Reynolds number).
/// A body of mass m then falls at v_t = √(m g / c_2): 6.7 m/s for a 2 mm raindrop (Gunn & Kinzer
/// measured 6.5). @throws std::invalid_argument unless all arguments are > 0.
double sphere_quadratic_drag(double diameter_mm, double air_density = 1.225,
                             double drag_coefficient = 0.47);

/// Drops per square metre per second for a rainfall rate `intensity_mm_h` (mm/h) made of drops
/// of diameter `diameter_mm` (mm): the water depth flux I / 3.6e6 (m/s) divided by one drop's
/// volume π D³ / 6. @throws std::invalid_argument unless both are > 0.
double rain_drops_per_m2_s(double intensity_mm_h, double diameter_mm);

/// Start speed (m/s) for a drop launched at `elevation_deg` above the horizon to reach
/// `apex_height_m` (m) above its start under gravity `g` without drag:
/// v0 = sqrt(2 g h) / sin(elevation). @throws std::invalid_argument unless h >= 0, g > 0 and
/// 0 < elevation_deg <= 90.
double launch_speed_for_apex(double apex_height_m, double elevation_deg, double g = 9.81);

/// Time (s) for a drop launched straight up at `speed` (m/s) to reach its apex, v0 / g.
double time_to_apex(double speed, double g = 9.81);

}  // namespace simreel::effects
