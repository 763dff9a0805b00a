// The recipes of Coutinho §3.9.1: effect knobs -> low-level emitters and force fields (scene
// JSON). Every number a recipe picks that is not a knob is named here with the reason for it.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "simreel/effects/effects.hpp"
#include "simreel/effects/physics.hpp"

namespace simreel::effects {

namespace {

using json = nlohmann::json;
constexpr double kPi = std::numbers::pi;

double num(const json& knobs, const char* key) {
  if (!knobs.contains(key) || !knobs.at(key).is_number())
    throw std::invalid_argument(std::string("effects::derive: knob ") + key + " missing or not a number");
  return knobs.at(key).get<double>();
}
std::array<double, 3> vec3(const json& knobs, const char* key) {
  if (!knobs.contains(key) || !knobs.at(key).is_array() || knobs.at(key).size() < 2)
    throw std::invalid_argument(std::string("effects::derive: knob ") + key + " missing or not an array");
  const json& a = knobs.at(key);
  return {a[0].get<double>(), a[1].get<double>(), a.size() > 2 ? a[2].get<double>() : 0.0};
}
std::string str(const json& knobs, const char* key) { return knobs.at(key).get<std::string>(); }
bool flag(const json& knobs, const char* key) { return knobs.at(key).get<bool>(); }

json dist(double mean, double deviation) { return {{"mean", mean}, {"deviation", deviation}}; }
json dist(double mean, double deviation, double min, double max) {
  return {{"mean", mean}, {"deviation", deviation}, {"min", min}, {"max", max}};
}
/// Scene colours are in [0, 1]; recipes write brighter-than-white emission (fire, sparks) as
/// values above 1 and let additive blending build the glow, so they are clamped here.
json rgba(double r, double g, double b, double a) {
  auto c = [](double x) { return std::clamp(x, 0.0, 1.0); };
  return json::array({c(r), c(g), c(b), c(a)});
}
json key(double t, const json& color) { return {{"t", t}, {"color", color}}; }
json vec(const std::array<double, 3>& v) { return json::array({v[0], v[1], v[2]}); }

/// Curl-noise turbulence and a steady drift for systems with no gravity: a uniform force
/// k_d u pulls a particle toward the air velocity u (its terminal velocity under drag alone is
/// then u, Coutinho §3.3.2), and the noise stirs it.
void add_air(Derived& d, const std::string& system, double drag, const std::array<double, 3>& air_velocity,
             double turbulence, double frequency) {
  d.force_fields.push_back({{"type", "uniform"},
                            {"force", json::array({drag * air_velocity[0], drag * air_velocity[1],
                                                   drag * air_velocity[2]})},
                            {"systems", json::array({system})}});
  if (turbulence > 0.0)
    d.force_fields.push_back({{"type", "curl_noise"},
                              {"amplitude", turbulence},
                              {"frequency", frequency},
                              // The swirl pattern drifts up with the smoke, so eddies travel.
                              {"scroll", json::array({0.0, 0.0, 0.5 * air_velocity[2]})},
                              {"drag", drag},
                              {"systems", json::array({system})}});
}

// ---------------------------------------------------------------------------------------------
// Smoke (§3.9.1): many small light particles, no gravity, an external force balanced by strong
// viscous drag, long lifespan, an early split age so the column starts dense, small split
// deviations that accumulate so it opens like a cone.

struct SmokeLook {
  std::array<double, 3> color;
  double alpha;
};

json smoke_emitter(const json& k, const std::string& name, double rise, double lifetime, double density,
                   double source_radius, const json& colors, double drag) {
  const double puff = std::max(0.06, 0.6 * source_radius);  // start radius of a puff (m)
  json e = {
      {"name", name},
      {"shape", "disk"},
      {"disk_radius", source_radius},
      {"position", vec(vec3(k, "position"))},
      {"direction", json::array({0, 0, 1})},
      {"rate", 110.0 * density},
      {"lifetime", dist(lifetime, 0.15 * lifetime, 0.3 * lifetime, 2.0 * lifetime)},
      {"start_speed", dist(rise, 0.15 * rise, 0.0, 3.0 * rise)},
      {"spread_deg", dist(0.0, 6.0)},
      {"mass", dist(2e-4, 2e-5, 1e-4, 4e-4)},
      {"particle_radius", dist(puff, 0.2 * puff, 0.3 * puff, 2.0 * puff)},
      {"gravity", json::array({0, 0, 0})},
      {"drag", drag},
      {"collide", false},
      {"color_over_lifetime", colors},
      // Puffs grow as they entrain air: about 3.5x their start size by the end of their life.
      {"size_over_lifetime", json::array({{{"t", 0.0}, {"size", 0.6}},
                                          {{"t", 0.3}, {"size", 1.6}},
                                          {{"t", 1.0}, {"size", 3.5}}})},
      // Split (§3.9.1): early, then again half a second later (120 internal steps at the default
      // 1/240 s), each time into 2 children deviating up to 25 degrees; the sideways kicks decay
      // only over the drag time (1 s), so the deviations accumulate and the column opens like a
      // cone as it rises. Each emitted puff becomes (2 + 1)^2 = 9.
      {"split", {{"enabled", true},
                 {"children", 2},
                 {"age", 0.08 * lifetime},
                 {"delay_steps", 120},
                 {"depth", 2},
                 {"velocity_fraction", 1.0},
                 {"direction_deviation_deg", 25.0},
                 {"size_fraction", 0.85},
                 {"lifetime_deviation", 0.15 * lifetime}}},
      {"render_style", "soft"},
      // Noise-textured puffs that turn and dissolve as they age, self-shadowed (issue 14).
      {"texture", "smoke"},
      {"max_particles", 60000}};
  return e;
}

Derived smoke(const json& k, const std::string& name) {
  Derived d;
  const double rise = num(k, "rise_speed_m_s"), life = num(k, "dissipation_s"), density = num(k, "density");
  const auto c = vec3(k, "color");
  // Opacity of one puff: a thin smoke at density 1 lets most light through each puff; many
  // overlapping puffs make the column read as dense.
  const double a = std::min(0.85, 0.30 * std::sqrt(density));
  const json colors = json::array({key(0.0, rgba(c[0], c[1], c[2], 0.0)), key(0.06, rgba(c[0], c[1], c[2], a)),
                                   key(0.5, rgba(c[0], c[1], c[2], 0.6 * a)),
                                   key(1.0, rgba(c[0], c[1], c[2], 0.0))});
  // Strong drag: the velocity relaxes to the air's in m / k_d = 1 s (mean mass 2e-4 kg).
  const double drag = 2e-4 / 1.0;
  d.emitters.push_back(smoke_emitter(k, name, rise, life, density, num(k, "source_radius_m"), colors, drag));
  d.emitters.back()["role"] = "smoke";
  const auto w = vec3(k, "wind_m_s");
  add_air(d, name, drag, {w[0], w[1], w[2] + rise}, num(k, "turbulence_m_s"), 1.1);
  return d;
}

// ---------------------------------------------------------------------------------------------
// Fire smoke (§3.9.1): yellow -> orange -> dark grey -> black over age; the material sets how
// long each stage lasts.

/// Ends of the yellow, orange and dark-grey stages as fractions of the smoke's life (black
/// after): a clean-burning material stays bright longer, a sooty one turns black soon.
std::array<double, 3> material_stages(const std::string& material) {
  if (material == "paper") return {0.18, 0.34, 0.75};
  if (material == "oil") return {0.07, 0.14, 0.35};
  if (material == "rubber") return {0.04, 0.09, 0.22};
  return {0.12, 0.24, 0.55};  // wood
}

Derived fire_smoke(const json& k, const std::string& name) {
  Derived d;
  const double rise = num(k, "rise_speed_m_s"), life = num(k, "dissipation_s"), density = num(k, "density");
  const double radius = num(k, "source_radius_m");
  const auto st = material_stages(str(k, "material"));
  const double a = std::min(0.9, 0.4 * std::sqrt(density));
  // Emissive stages are brighter than 1 (HDR; the renderer tone-maps them).
  const json colors = json::array({key(0.0, rgba(1.6, 1.3, 0.35, 0.0)), key(0.3 * st[0], rgba(1.6, 1.25, 0.3, a)),
                                   key(st[0], rgba(1.4, 0.95, 0.2, a)), key(st[1], rgba(1.1, 0.45, 0.08, a)),
                                   key(0.5 * (st[1] + st[2]), rgba(0.28, 0.25, 0.23, 0.9 * a)),
                                   key(st[2], rgba(0.16, 0.15, 0.145, 0.85 * a)),
                                   // Wood smoke thins out dark grey, not black.
                                   key(1.0, rgba(0.12, 0.115, 0.11, 0.0))});
  const double drag = 2e-4 / 1.0;
  json smoke_e = smoke_emitter(k, name + "/smoke", rise, life, density, radius, colors, drag);
  smoke_e["role"] = "smoke";
  d.emitters.push_back(smoke_e);

  // The flame core: short-lived additive particles just above the source, rising faster.
  json core = {{"name", name + "/core"},
               {"role", "core"},
               {"shape", "disk"},
               {"disk_radius", 0.8 * radius},
               {"position", vec(vec3(k, "position"))},
               {"direction", json::array({0, 0, 1})},
               {"rate", 500.0 * density},
               {"lifetime", dist(0.45, 0.12, 0.1, 0.9)},
               {"start_speed", dist(1.6 * rise, 0.3 * rise, 0.0, 4.0 * rise)},
               {"spread_deg", dist(0.0, 10.0)},
               {"mass", dist(2e-4, 0.0)},
               {"particle_radius", dist(0.5 * radius, 0.1 * radius, 0.1 * radius, radius)},
               {"gravity", json::array({0, 0, 0})},
               {"drag", drag},
               {"collide", false},
               {"color_over_lifetime", json::array({key(0.0, rgba(1.8, 1.5, 0.6, 0.0)),
                                                     key(0.15, rgba(1.8, 1.2, 0.35, 0.55)),
                                                     key(0.6, rgba(1.4, 0.5, 0.08, 0.35)),
                                                     key(1.0, rgba(0.6, 0.12, 0.02, 0.0))})},
               {"size_over_lifetime", json::array({{{"t", 0.0}, {"size", 1.0}}, {{"t", 1.0}, {"size", 0.35}}})},
               {"render_style", "additive"},
               // Colour from the temperature ramp (white-yellow -> orange -> red), flickering,
               // in noise tongues; brighter than 1 so the bloom pass makes it glow.
               {"texture", "flame"},
               {"emissive", 1.3},
               {"max_particles", 20000}};
  d.emitters.push_back(core);
  const auto w = vec3(k, "wind_m_s");
  add_air(d, name + "/smoke", drag, {w[0], w[1], w[2] + rise}, num(k, "turbulence_m_s"), 1.2);
  add_air(d, name + "/core", drag, {w[0], w[1], w[2] + 1.6 * rise}, 0.5 * num(k, "turbulence_m_s"), 2.0);
  return d;
}

// ---------------------------------------------------------------------------------------------
// Rain (§3.9.1): an emitter surface covering the area; gravity plus quadratic air drag
// c_2 = ½ ρ_air C_d π r² (sphere, C_d = 0.47, ρ_air = 1.225 kg/m³) give the fall speed
// v_t = √(m g / c_2); intensity and drop size set count and mass.

Derived rain(const json& k, const std::string& name, double g) {
  Derived d;
  const double dmm = num(k, "drop_diameter_mm");
  const double m = drop_mass(dmm);
  const double c2 = sphere_quadratic_drag(dmm);
  const double vt = std::sqrt(m * g / c2);
  const auto area = vec3(k, "area_m");
  const auto c = vec3(k, "center");
  const auto w = vec3(k, "wind_m_s");
  const double h = num(k, "height_m");
  const double rate = std::min(num(k, "max_drops_per_s"),
                               rain_drops_per_m2_s(num(k, "intensity_mm_h"), dmm) * area[0] * area[1]);
  // Drops fall at v = (w_x, w_y, -v_t): release them upwind so the wet area stays over center.
  const double fall_time = h / vt;
  const std::array<double, 3> top{c[0] - w[0] * fall_time, c[1] - w[1] * fall_time, c[2] + h};
  const std::array<double, 3> v{w[0], w[1], -vt};
  const double speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  json e = {{"name", name},
            {"role", "drops"},
            {"shape", "quad"},
            {"quad_size", json::array({area[0], area[1]})},
            {"position", vec(top)},
            {"direction", json::array({v[0] / speed, v[1] / speed, v[2] / speed})},
            {"rate", rate},
            {"lifetime", dist(1.5 * fall_time + 0.5, 0.0)},
            {"start_speed", dist(speed, 0.03 * speed, 0.0, 2.0 * speed)},
            {"spread_deg", dist(0.0, 0.5)},
            {"mass", dist(m, 0.0)},
            // Drawn radius: a real 2 mm drop is under a pixel at video sizes; the streak (motion
            // blur over streak_s seconds, about a camera shutter) carries it.
            {"particle_radius", dist(0.5 * dmm * 1e-3 * 3.0, 0.0)},
            {"drag_quadratic", c2},
            {"color", json::array({0.80, 0.85, 0.95, 0.75})},
            {"render_style", "streak"},
            {"streak_s", 0.045},
            {"max_particles", std::size_t(std::min(2e6, rate * (1.5 * fall_time + 0.5) + 1000))}};
  // The area moves with the camera (its ground point): the rain fills the view as the camera
  // travels, near drops streaking past the lens.
  if (flag(k, "follow_camera")) e["follow_camera"] = true;
  if (flag(k, "splash")) {
    // Each drop that lands throws a few small droplets up and out (the §3.9.1 rain splash).
    e["on_hit"] = "split";
    e["on_hit_split"] = {{"count", 3},
                         {"speed_fraction", 0.22},
                         {"size_fraction", 0.45},
                         {"lifetime", 0.3},
                         {"spread_deg", 55.0},
                         {"min_radius", 0.5 * dmm * 1e-3 * 2.5 * 0.9}};
  } else {
    e["on_hit"] = "kill";  // drops soak in
  }
  d.emitters.push_back(e);
  // Wind: the drag acts on the ground-frame velocity, so a uniform force
  // F = c_2 |v*| v* - m g_vec makes v* = (w_x, w_y, w_z - v_t) (the drop drifting with the air at
  // its still-air fall speed) the steady velocity: horizontally c_2 |v*| w.
  if (w[0] != 0.0 || w[1] != 0.0 || w[2] != 0.0) {
    const double s = c2 * speed;
    d.force_fields.push_back({{"type", "uniform"},
                              {"force", json::array({s * v[0], s * v[1], s * v[2] + m * g})},
                              {"systems", json::array({name})}});
  }
  return d;
}

// ---------------------------------------------------------------------------------------------
// Sprinkler and jet (§3.9.1): parabolic drops; start speed from the apex height; deviation is
// the aperture.

json rotation_keys(double elevation_deg, double azimuth_deg, double rpm, const std::array<double, 3>& pos) {
  // Emitters fire along their local +z; tilt it down to the elevation, then turn it about z.
  const double tilt = 90.0 - elevation_deg;
  json keys = json::array();
  const double period = 60.0 / std::abs(rpm);
  for (int i = 0; i <= 8; ++i) {
    const double t = period * i / 8.0;
    const double az = azimuth_deg + (rpm > 0 ? 1.0 : -1.0) * 360.0 * i / 8.0;
    keys.push_back({{"time", t}, {"position", vec(pos)}, {"rotation_deg", json::array({0.0, tilt, az})}});
  }
  return {{"loop", true}, {"smooth", false}, {"keys", keys}};
}

Derived sprinkler(const json& k, const std::string& name, double g) {
  Derived d;
  const double elev = num(k, "elevation_deg"), az = num(k, "azimuth_deg"), rpm = num(k, "rotation_rpm");
  const double v0 = launch_speed_for_apex(num(k, "max_height_m"), elev, g);
  const auto pos = vec3(k, "position");
  const double r = num(k, "drop_radius_m");
  const double e_rad = elev * kPi / 180.0, a_rad = az * kPi / 180.0;
  json e = {{"name", name},
            {"role", "drops"},
            {"shape", "disk"},
            {"disk_radius", 0.01},
            {"position", vec(pos)},
            {"direction", json::array({std::cos(e_rad) * std::cos(a_rad), std::cos(e_rad) * std::sin(a_rad),
                                        std::sin(e_rad)})},
            {"rate", num(k, "flow_drops_s")},
            {"lifetime", dist(4.0, 0.3)},
            {"start_speed", dist(v0, 0.02 * v0, 0.5 * v0, 1.5 * v0)},
            {"spread_deg", dist(0.0, num(k, "aperture_deg"))},
            {"mass", dist(4.0 / 3.0 * kPi * r * r * r * kWaterDensity * 0.05, 0.0)},
            {"particle_radius", dist(r, 0.25 * r, 0.3 * r, 2.0 * r)},
            {"color_over_lifetime", json::array({key(0.0, rgba(0.6, 0.82, 1.0, 0.9)),
                                                  key(0.8, rgba(0.3, 0.55, 0.95, 0.8)),
                                                  key(1.0, rgba(0.3, 0.55, 0.95, 0.0))})},
            {"render_style", "droplet"},
            {"max_particles", 100000}};
  if (rpm != 0.0) e["path"] = rotation_keys(elev, az, rpm, pos);
  d.emitters.push_back(e);
  return d;
}

Derived jet(const json& k, const std::string& name) {
  Derived d;
  const auto dir = vec3(k, "direction");
  const double r = num(k, "drop_radius_m");
  json e = {{"name", name},
            {"role", "drops"},
            {"shape", "disk"},
            {"disk_radius", 1.5 * r},
            {"position", vec(vec3(k, "position"))},
            {"direction", vec(dir)},
            {"rate", num(k, "rate")},
            {"lifetime", dist(3.0, 0.2)},
            {"start_speed", dist(num(k, "speed_m_s"), 0.01 * num(k, "speed_m_s"))},
            {"spread_deg", dist(0.0, num(k, "deviation_deg"))},
            {"mass", dist(num(k, "drop_mass_kg"), 0.0)},
            {"particle_radius", dist(r, 0.1 * r, 0.5 * r, 1.5 * r)},
            {"color", json::array({0.45, 0.7, 1.0, 0.95})},
            {"render_style", "droplet"},
            {"max_particles", 100000}};
  d.emitters.push_back(e);
  return d;
}

// ---------------------------------------------------------------------------------------------
// Explosion (§3.9.1): a burst from a spherical or planar emitter, many small particles, short
// lifespan, large deviation, heavy splitting; no external forces.

Derived explosion(const json& k, const std::string& name) {
  Derived d;
  const bool sphere = str(k, "shape") == "sphere";
  const double t = num(k, "time_s"), speed = num(k, "blast_speed_m_s"), radius = num(k, "radius_m");
  const double life = num(k, "dissipation_s");
  const auto pos = vec3(k, "position");
  const long long n = k.at("particles").get<long long>();
  const long long children = k.at("split_children").get<long long>();
  auto base = [&](const std::string& role, long long count) {
    json e = {{"name", name + "/" + role},
              {"role", role},
              {"position", vec(pos)},
              {"direction", json::array({0, 0, 1})},
              {"rate", 0},
              {"bursts", json::array({{{"time", t}, {"count", count}}})},
              {"collide", true}};
    if (sphere) {
      e["shape"] = "sphere";
      e["sphere_radius"] = radius;
    } else {
      e["shape"] = "disk";
      e["disk_radius"] = radius;
    }
    return e;
  };
  json sparks = base("sparks", n);
  sparks["lifetime"] = dist(0.7, 0.3, 0.1, 2.0);
  sparks["start_speed"] = dist(1.4 * speed, 0.35 * speed, 0.1 * speed, 3.0 * speed);
  sparks["spread_deg"] = dist(0.0, sphere ? 25.0 : 55.0);
  sparks["mass"] = dist(2e-4, 5e-5, 5e-5, 1e-3);
  sparks["particle_radius"] = dist(0.05, 0.015, 0.02, 0.1);
  sparks["drag"] = 2e-4;
  sparks["color_over_lifetime"] = json::array({key(0.0, rgba(2.0, 1.6, 0.7, 1.0)), key(0.4, rgba(1.6, 0.7, 0.15, 0.9)),
                                               key(1.0, rgba(0.6, 0.1, 0.02, 0.0))});
  sparks["render_style"] = "additive";
  sparks["trail_s"] = 0.05;  // fast sparks streak
  sparks["emissive"] = 1.5;
  sparks["max_particles"] = n + 10;
  d.emitters.push_back(sparks);

  json smoke = base("smoke", std::max<long long>(1, n / 4));
  smoke["lifetime"] = dist(life, 0.25 * life, 0.2 * life, 2.0 * life);
  smoke["start_speed"] = dist(0.6 * speed, 0.3 * speed, 0.0, 1.5 * speed);
  smoke["spread_deg"] = dist(0.0, sphere ? 30.0 : 60.0);
  smoke["mass"] = dist(2e-4, 2e-5, 1e-4, 4e-4);
  smoke["particle_radius"] = dist(2.0 * radius, 0.4 * radius, 0.5 * radius, 4.0 * radius);
  smoke["gravity"] = json::array({0, 0, 0});
  // Heavy drag stops the cloud within a metre or two: it billows rather than flies.
  smoke["drag"] = 2e-4 / 0.18;
  smoke["color_over_lifetime"] =
      json::array({key(0.0, rgba(1.0, 0.75, 0.35, 0.5)), key(0.06, rgba(0.42, 0.36, 0.31, 0.4)),
                   key(0.5, rgba(0.3, 0.29, 0.28, 0.25)), key(1.0, rgba(0.28, 0.28, 0.28, 0.0))});
  smoke["size_over_lifetime"] = json::array({{{"t", 0.0}, {"size", 0.5}}, {{"t", 1.0}, {"size", 2.5}}});
  if (children > 0)
    smoke["split"] = {{"enabled", true},
                      {"children", children},
                      {"age", 0.05},
                      {"delay_steps", 1},
                      {"depth", 2},
                      {"velocity_fraction", 0.7},
                      {"direction_deviation_deg", 35.0},
                      {"size_fraction", 0.8},
                      {"lifetime_deviation", 0.2 * life}};
  smoke["render_style"] = "soft";
  smoke["texture"] = "smoke";
  smoke["max_particles"] = 200000;
  d.emitters.push_back(smoke);

  // The fireball: a few large flame sprites that swell over ~0.7 s while their temperature ramp
  // cools them from white-yellow through orange to red embers, rising a little (buoyancy), as
  // the smoke above takes over.
  const long long balls = std::clamp<long long>(n / 25, 8, 120);
  json fireball = base("fireball", balls);
  fireball["lifetime"] = dist(0.75, 0.15, 0.35, 1.2);
  fireball["start_speed"] = dist(0.25 * speed, 0.08 * speed, 0.0, 0.5 * speed);
  fireball["spread_deg"] = dist(0.0, sphere ? 90.0 : 45.0);
  fireball["mass"] = dist(2e-4, 0.0);
  fireball["particle_radius"] = dist(2.2 * radius, 0.5 * radius, 1.0 * radius, 4.0 * radius);
  fireball["gravity"] = json::array({0, 0, 1.5});
  fireball["drag"] = 2e-4 / 0.12;
  fireball["collide"] = false;
  fireball["color_over_lifetime"] = json::array({key(0.0, rgba(1, 1, 1, 0.9)), key(0.5, rgba(1, 1, 1, 0.6)),
                                                 key(1.0, rgba(1, 1, 1, 0.0))});
  fireball["size_over_lifetime"] = json::array({{{"t", 0.0}, {"size", 0.6}}, {{"t", 1.0}, {"size", 2.6}}});
  fireball["render_style"] = "additive";
  fireball["texture"] = "flame";
  fireball["emissive"] = 2.0;
  fireball["max_particles"] = balls + 4;
  d.emitters.push_back(fireball);

  // The dust ring: the blast's wave raises dust from the ground under it, rolling outwards.
  if (flag(k, "dust_ring")) {
    json dust = base("dust", std::max<long long>(40, n / 5));
    dust["shape"] = "disk";
    dust["disk_radius"] = std::max(0.3, 2.0 * radius);
    dust["position"] = json::array({pos[0], pos[1], num(k, "ground_z_m") + 0.05});
    dust["bursts"] = json::array({{{"time", t + 0.05}, {"count", std::max<long long>(40, n / 5)}}});
    dust["lifetime"] = dist(0.9 * life, 0.2 * life, 0.3 * life, 2.0 * life);
    dust["start_speed"] = dist(0.6 * speed, 0.15 * speed, 0.1 * speed, 1.2 * speed);
    dust["spread_deg"] = dist(84.0, 3.0, 75.0, 89.0);  // nearly flat: outwards along the ground
    dust["mass"] = dist(2e-4, 2e-5, 1e-4, 4e-4);
    dust["particle_radius"] = dist(0.35, 0.08, 0.15, 0.6);
    dust["gravity"] = json::array({0, 0, 0});
    dust["drag"] = 2e-4 / 0.35;  // stops within ~2 m: a ring, not a spray
    dust["collide"] = false;
    dust["color_over_lifetime"] = json::array({key(0.0, rgba(0.5, 0.43, 0.34, 0.0)), key(0.08, rgba(0.5, 0.43, 0.34, 0.4)),
                                               key(1.0, rgba(0.46, 0.41, 0.35, 0.0))});
    dust["size_over_lifetime"] = json::array({{{"t", 0.0}, {"size", 0.6}}, {{"t", 1.0}, {"size", 2.4}}});
    dust["render_style"] = "soft";
    dust["texture"] = "smoke";
    dust["max_particles"] = std::max<long long>(40, n / 5) + 4;
    d.emitters.push_back(dust);
  }
  return d;
}

// ---------------------------------------------------------------------------------------------
// Fireworks (§3.9.1): a shell rises and bursts at its apex from a spherical emitter along
// radial directions, with direction and speed deviation for an uneven shell; coloured trails.

std::array<double, 3> palette_color(const std::string& palette, long long shell) {
  static const std::array<std::array<double, 3>, 6> festival{
      {{1.8, 0.35, 0.3}, {0.4, 1.6, 0.5}, {0.5, 0.7, 2.0}, {1.8, 1.4, 0.4}, {1.5, 0.5, 1.8}, {0.4, 1.6, 1.7}}};
  if (palette == "gold") return {1.9, 1.3, 0.45};
  if (palette == "green") return {0.45, 1.8, 0.5};
  if (palette == "violet") return {1.3, 0.45, 1.9};
  if (palette == "red_white_blue") {
    static const std::array<std::array<double, 3>, 3> rwb{{{1.9, 0.3, 0.3}, {1.7, 1.7, 1.7}, {0.4, 0.6, 2.0}}};
    return rwb[std::size_t(shell % 3)];
  }
  return festival[std::size_t(shell % 6)];
}

/// Flashes per crackling star: a dense enough cloud to read as crackle at video sizes.
constexpr long long kCrackleFlashes = 30;

Derived fireworks(const json& k, const std::string& name, double g) {
  Derived d;
  const auto launch = vec3(k, "launch_position");
  const double h = num(k, "burst_height_m"), interval = num(k, "interval_s"), spacing = num(k, "spacing_m");
  const double v0 = launch_speed_for_apex(h, 90.0, g);
  const double t_apex = time_to_apex(v0, g);
  const long long shells = k.at("shells").get<long long>();
  const long long stars = k.at("stars").get<long long>();
  const double burst = num(k, "burst_speed_m_s");
  for (long long s = 0; s < shells; ++s) {
    const std::array<double, 3> p{launch[0] + spacing * (double(s) - 0.5 * double(shells - 1)), launch[1],
                                  launch[2]};
    const double t_launch = 0.2 + interval * double(s);
    const std::string sn = name + "/shell" + std::to_string(s);
    // The rising shell: one bright particle on a ballistic path, dying at the apex.
    d.emitters.push_back({{"name", sn},
                          {"role", "shell"},
                          {"shape", "point"},
                          {"position", vec(p)},
                          {"direction", json::array({0, 0, 1})},
                          {"rate", 0},
                          {"bursts", json::array({{{"time", t_launch}, {"count", 1}}})},
                          {"lifetime", dist(t_apex, 0.0)},
                          {"start_speed", dist(v0, 0.0)},
                          {"mass", dist(0.05, 0.0)},
                          {"particle_radius", dist(0.14, 0.0)},
                          {"color", rgba(1.8, 1.3, 0.6, 1.0)},
                          {"render_style", "additive"},
                          // Visible while it rises: a glowing trail of its last 0.25 s.
                          {"trail_s", 0.25},
                          {"emissive", 2.0},
                          {"collide", false},
                          {"max_particles", 4}});
    const auto c = palette_color(str(k, "palette"), s);
    json e = {{"name", name + "/stars" + std::to_string(s)},
              {"role", "stars"},
              {"shape", "sphere"},
              {"sphere_radius", 0.15},
              {"position", json::array({p[0], p[1], p[2] + h})},
              {"direction", json::array({0, 0, 1})},
              {"rate", 0},
              {"bursts", json::array({{{"time", t_launch + t_apex}, {"count", stars}}})},
              {"lifetime", dist(2.2, 0.4, 0.8, 3.5)},
              {"start_speed", dist(burst, num(k, "speed_deviation") * burst, 0.1 * burst, 2.0 * burst)},
              {"spread_deg", dist(0.0, 6.0)},
              {"mass", dist(2e-3, 2e-4, 1e-3, 4e-3)},
              {"particle_radius", dist(0.2, 0.04, 0.1, 0.3)},
              // Drag relaxes the burst in ~1 s so the shell hangs, then droops under gravity.
              {"drag", 2e-3 / 1.2},
              {"collide", false},
              {"color_over_lifetime", json::array({key(0.0, rgba(2.0, 2.0, 2.0, 1.0)),
                                                    key(0.12, rgba(c[0], c[1], c[2], 1.0)),
                                                    key(0.75, rgba(0.6 * c[0], 0.6 * c[1], 0.6 * c[2], 0.7)),
                                                    key(1.0, rgba(0.2 * c[0], 0.2 * c[1], 0.2 * c[2], 0.0))})},
              {"render_style", "additive"},
              {"trail_s", 0.12},  // stars streak as they fly out, then shorten as drag slows them
              {"emissive", 1.5},
              {"max_particles", stars * 33 + 10}};
    // Trails: each star sheds a slow spark every 0.1 s (split, §3.9.1); the sparks inherit the
    // star's age (± a little) so they fade with it, and split again: 2^5 = 32 points per star.
    if (flag(k, "trails"))
      e["split"] = {{"enabled", true},
                    {"children", 1},
                    {"age", 0.08},
                    {"delay_steps", 24},
                    {"depth", 5},
                    {"velocity_fraction", 0.25},
                    {"direction_deviation_deg", 40.0},
                    {"size_fraction", 0.7},
                    {"lifetime_deviation", 0.25}};
    // Crackle: a star that burns out breaks into a cloud of tiny white-gold flashes popping on
    // and off (a sub-emitter on death, Unity's "Sub Emitters"; Houdini's source from particles).
    // The cloud starts at the dying star with its velocity and spreads at a few m/s, held by
    // strong drag (0.3 s) so it stays a tight ball; each flash strobes at its own phase.
    const double crackle = num(k, "crackle");
    if (crackle > 0.0) {
      const std::string cn = name + "/crackle" + std::to_string(s);
      e["sub_emitters"] = json::array({{{"emitter", cn},
                                        {"trigger", "death"},
                                        {"count", kCrackleFlashes},
                                        {"probability", crackle},
                                        {"inherit_velocity", 1.0},
                                        // a star's trail sparks die with it but do not crackle
                                        {"split_children", false}}});
      d.emitters.push_back(e);
      d.emitters.push_back({{"name", cn},
                            {"role", "crackle"},
                            {"shape", "sphere"},
                            {"sphere_radius", 0.05},
                            {"position", json::array({p[0], p[1], p[2] + h})},
                            {"rate", 0},
                            {"lifetime", {{"min", 0.45}, {"max", 1.0}}},
                            {"start_speed", dist(2.5, 1.0, 0.5, 5.0)},
                            {"mass", dist(2e-4, 0.0)},
                            {"particle_radius", dist(0.045, 0.012, 0.02, 0.07)},
                            {"drag", 2e-4 / 0.3},
                            {"collide", false},
                            {"color_over_lifetime", json::array({key(0.0, rgba(1.0, 1.0, 0.95, 1.0)),
                                                                  key(0.6, rgba(1.0, 0.85, 0.5, 1.0)),
                                                                  key(1.0, rgba(1.0, 0.6, 0.25, 0.6))})},
                            {"render_style", "additive"},
                            {"emissive", 10.0},
                            {"strobe_hz", 12.0},
                            {"strobe_duty", 0.35},
                            {"max_particles",
                             (long long)(std::ceil(crackle * double(stars))) * kCrackleFlashes + 10}});
      continue;
    }
    d.emitters.push_back(e);
  }
  return d;
}

}  // namespace

Derived derive(const EffectSpec& spec, const json& knobs, const std::string& base_name, double gravity_z) {
  const double g = gravity_z < 0.0 ? -gravity_z : 9.81;
  const std::string& n = spec.name;
  if (n == "smoke") return smoke(knobs, base_name);
  if (n == "fire_smoke") return fire_smoke(knobs, base_name);
  if (n == "rain") return rain(knobs, base_name, g);
  if (n == "sprinkler") return sprinkler(knobs, base_name, g);
  if (n == "jet") return jet(knobs, base_name);
  if (n == "explosion") return explosion(knobs, base_name);
  if (n == "fireworks") return fireworks(knobs, base_name, g);
  throw std::invalid_argument("effects::derive: no recipe for effect \"" + n + "\"");
}

}  // namespace simreel::effects
