#pragma once
/// @file jets.hpp
/// Physical knobs of water jets (Coutinho §3.9.1, sprinklers and jet flows): for a drop
/// under gravity alone the trajectory is a parabola, and the start speed sets the apex height.

namespace simreel::effects {

/// Start speed (m/s) of a vertical jet whose drops reach `height_m` (m) above the nozzle under
/// gravity `g` (m/s², > 0), without drag: v0 = sqrt(2 g h). @throws std::invalid_argument if
/// height_m < 0 or g <= 0.
double vertical_jet_speed(double height_m, double g = 9.81);

/// Apex height (m) above the nozzle of a drop launched at `speed` (m/s) and `elevation_deg`
/// above the horizon, without drag: h = (v sin θ)² / (2 g).
double apex_height(double speed, double elevation_deg, double g = 9.81);

}  // namespace simreel::effects
