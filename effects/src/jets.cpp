#include "simreel/effects/jets.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace simreel::effects {

double vertical_jet_speed(double height_m, double g) {
  if (!(height_m >= 0.0) || !(g > 0.0))
    throw std::invalid_argument("vertical_jet_speed: expected height_m >= 0 and g > 0");
  return std::sqrt(2.0 * g * height_m);
}

double apex_height(double speed, double elevation_deg, double g) {
  if (!(g > 0.0)) throw std::invalid_argument("apex_height: expected g > 0");
  const double vz = speed * std::sin(elevation_deg * std::numbers::pi / 180.0);
  return vz * vz / (2.0 * g);
}

}  // namespace simreel::effects
