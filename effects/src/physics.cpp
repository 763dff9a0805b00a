// Knob physics of the effects layer (Coutinho §3.9.1, §3.3.2).
#include "simreel/effects/physics.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace simreel::effects {

namespace {
[[noreturn]] void bad(const char* what) { throw std::invalid_argument(what); }
}  // namespace

double drop_mass(double diameter_mm) {
  if (!(diameter_mm > 0.0)) bad("drop_mass: expected diameter_mm > 0");
  const double d = diameter_mm * 1e-3;
  return kWaterDensity * std::numbers::pi * d * d * d / 6.0;
}

double raindrop_terminal_velocity(double diameter_mm) {
  if (!(diameter_mm >= 0.3 && diameter_mm <= 6.0))
    bad("raindrop_terminal_velocity: expected 0.3 <= diameter_mm <= 6 (the fit's range)");
  return 9.65 - 10.3 * std::exp(-0.6 * diameter_mm);
}

double drag_for_terminal_velocity(double mass, double terminal_speed, double g) {
  if (!(mass > 0.0) || !(terminal_speed > 0.0) || !(g > 0.0))
    bad("drag_for_terminal_velocity: expected mass, terminal_speed and g > 0");
  return mass * g / terminal_speed;
}

double sphere_quadratic_drag(double diameter_mm, double air_density, double drag_coefficient) {
  if (!(diameter_mm > 0.0) || !(air_density > 0.0) || !(drag_coefficient > 0.0))
    bad("sphere_quadratic_drag: expected diameter_mm, air_density and drag_coefficient > 0");
  const double r = 0.5e-3 * diameter_mm;
  return 0.5 * air_density * drag_coefficient * 3.14159265358979323846 * r * r;
}

double rain_drops_per_m2_s(double intensity_mm_h, double diameter_mm) {
  if (!(intensity_mm_h > 0.0) || !(diameter_mm > 0.0))
    bad("rain_drops_per_m2_s: expected intensity_mm_h > 0 and diameter_mm > 0");
  const double flux = intensity_mm_h * 1e-3 / 3600.0;  // m³ of water per m² per s
  const double d = diameter_mm * 1e-3;
  return flux / (std::numbers::pi * d * d * d / 6.0);
}

double launch_speed_for_apex(double apex_height_m, double elevation_deg, double g) {
  if (!(apex_height_m >= 0.0) || !(g > 0.0) || !(elevation_deg > 0.0 && elevation_deg <= 90.0))
    bad("launch_speed_for_apex: expected apex_height_m >= 0, g > 0, 0 < elevation_deg <= 90");
  return std::sqrt(2.0 * g * apex_height_m) / std::sin(elevation_deg * std::numbers::pi / 180.0);
}

double time_to_apex(double speed, double g) {
  if (!(g > 0.0)) bad("time_to_apex: expected g > 0");
  return speed / g;
}

}  // namespace simreel::effects
