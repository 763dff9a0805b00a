// `simreel schema`: a JSON Schema (draft 2020-12) of scene files, generated from what the
// loader's readers read (KeyLog: every key with its type, range and default) and from the
// effect presets' knob tables, so that editors complete and check scenes as the loader does.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "run_options.hpp"
#include "simreel/sim/ranges.hpp"
#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/effects/effects.hpp"
#include "simreel/render/atomic_file.hpp"

namespace simreel::app {

namespace {

using ojson = nlohmann::ordered_json;

/// Scenes that make every reader read every key it knows: each kind of collider, emitter
/// extras, force field, pin and path appears once. Keys of the same array (all collider types)
/// share one object schema: the schema is a little looser than the loader there.
const char* kProbe = R"({
  "simulation": {}, "render": {"bloom": {}}, "light": {},
  "camera": {"path": [{"time": 0, "target": [0, 0, 1]}], "orbit": {}},
  "colliders": [
    {"type": "plane", "material": {}, "collider": {"on_hit": "split", "split": {}, "static_friction": 1},
     "on_hit": "split", "split": {}, "static_friction": 1},
    {"type": "box", "path": {"keys": [{"time": 0}]}, "motion": "dynamic"},
    {"type": "sphere", "motion": "kinematic"},
    {"type": "cylinder"},
    {"type": "mesh", "scale": 1},
    {"type": "mesh", "scale": [1, 1, 1]},
    {"type": "capsule", "motion": "dynamic"}
  ],
  "bodies": [
    {"shape": "sphere", "mass": 1, "material": {"texture": "t.png", "static_friction": 1}},
    {"shapes": [{"type": "sphere", "material": {"static_friction": 1, "color": [1, 0, 0], "texture": "t.png"}}, {"type": "box"}, {"type": "capsule"}, {"type": "cylinder"},
                {"type": "convex_hull", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]},
                {"type": "convex_hull", "mesh": "m.obj", "scale": 1},
                {"type": "mesh", "mesh": "m.obj", "scale": [1, 1, 1]}]},
    {"type": "kinematic", "shape": "cylinder", "path": {"keys": [{"time": 0}]}},
    {"shape": "box"}, {"shape": "convex_hull", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]},
    {"shape": "mesh", "mesh": "m.obj", "scale": 1}
  ],
  "chains": [{"from": [0, 0, 1], "to": [1, 0, 1]}],
  "ragdolls": [{}],
  "joints": [{"type": "hinge", "body_a": "world", "body_b": "x", "limits": {}, "motor": {}},
             {"type": "spherical", "limits": {}}],
  "springs": [{"body_a": "world", "body_b": "x", "anchor_a": [0, 0, 2], "anchor_b": [0, 0, 1], "stiffness": 1}],
  "emitters": [{"name": "a", "shape": "mesh", "bursts": [{"count": 1}], "size_over_lifetime": [{}],
                "split": {}, "color_over_lifetime": [{}], "path": {"keys": [{"time": 0}]},
                "on_hit": "split", "on_hit_split": {}, "pair_forces": {}, "initial_particles": [{}],
                "springs": [{}], "sub_emitters": [{"emitter": "a"}]}],
  "force_fields": [{"type": "uniform", "region": {"shape": "box"}, "path": {"keys": [{"time": 0}]}},
                   {"type": "attractor", "region": {"shape": "sphere"}}, {"type": "vortex"}, {"type": "curl_noise"},
                   {"type": "blast"}],
  "attractor_springs": [{"path": {"keys": [{"time": 0}]}}],
  "cloths": [{"pins": [{"path": {"keys": [{"time": 0}]}}], "wind": {}, "aero": {}},
             {"mesh": "probe.obj", "scale": 1, "pins": [{"vertex": 0}, {"box_min": [0, 0, 0], "box_max": [0, 0, 0]}, {"group": "probe"}]},
             {"mesh": "probe.obj", "scale": [1, 1, 1]},
             {"pins": "top_edge", "areal_density": 1}]
})";

/// Units of scene keys (README "Scene format"); keys ending in _deg, _s or _m say theirs.
std::string unit_of(const std::string& object, const std::string& key) {
  static const std::vector<std::pair<std::string, std::string>> units = {
      {"fps", "1/s"}, {"max_step", "s"}, {"gravity", "m/s^2"}, {"contact_speed", "m/s"}, {"max_speed", "m/s"},
      {"max_distance", "m"}, {"width", "pixels"}, {"height", "pixels"}, {"position", "m"}, {"target", "m"},
      {"center", "m"}, {"radius", "m"}, {"point", "m"}, {"half_extents", "m"}, {"half_height", "m"},
      {"time", "s"}, {"lifetime", "s"}, {"start_time", "s"}, {"stop_time", "s"}, {"rate", "particles/s"},
      {"start_speed", "m/s"}, {"mass", "kg"}, {"particle_radius", "m"}, {"disk_radius", "m"},
      {"sphere_radius", "m"}, {"quad_size", "m"}, {"box_size", "m"}, {"cube_size", "m"},
      {"drag", "1/s (kg/s per kg)"}, {"drag_quadratic", "kg/m"}, {"velocity", "m/s"},
      {"angular_velocity", "rad/s"}, {"density", "kg/m^3"}, {"strength", "m/s^2"}, {"size", "m"},
      {"repeat_interval", "s"}, {"age", "s"}, {"stiffness", "N/m"}, {"damping", "N s/m"},
      {"rest_length", "m"}, {"spacing", "m"}, {"thickness", "m"}, {"cutoff", "m"}, {"streak_s", "s"}, {"strobe_hz", "Hz"},
      {"min_radius", "m"}, {"lifetime_deviation", "s"}, {"anchor", "m"}, {"from", "m"}, {"to", "m"},
      {"break_force_n", "N"}, {"max_torque_n_m", "N m"}, {"rpm", "rev/min"}, {"speed_deg_s", "deg/s"},
      {"height_m", "m"}, {"mass_kg", "kg"}, {"slack", "fraction of the straight length"},
      {"joint_damping", "N m s/rad"}};
  if (object.rfind("/camera", 0) == 0 && key == "height") return "m (above center)";
  if (object.rfind("/render", 0) == 0 && (key == "width" || key == "height")) return "pixels";
  auto ends = [&](const char* suffix) {
    const std::string s(suffix);
    return key.size() > s.size() && key.compare(key.size() - s.size(), s.size(), s) == 0;
  };
  if (key == "angular_velocity_deg") return "deg/s";
  if (key == "speed_deg_s") return "deg/s";
  if (key == "max_torque_n_m") return "N m";
  if (key == "break_force_n") return "N";
  if (key == "damping" && (object.rfind("/joints", 0) == 0 || object.rfind("/chains", 0) == 0)) return "N m s/rad";
  if (ends("_deg")) return "degrees";
  if (ends("_s")) return "s";
  if (ends("_m")) return "m";
  if (key.find("color") != std::string::npos || key.find("ambient") != std::string::npos ||
      key.rfind("sky_", 0) == 0)
    return "linear RGB(A), each in [0, 1]";
  for (const auto& [k, u] : units)
    if (k == key) return u;
  return "";
}

/// "in [0, 1]" / ">= 0" / "> 0" from a schema's bounds ("" for none).
std::string range_text(const json& s) {
  const bool lo = s.contains("minimum") || s.contains("exclusiveMinimum");
  const bool hi = s.contains("maximum");
  const double min = s.contains("minimum") ? s["minimum"].get<double>()
                     : lo                  ? s["exclusiveMinimum"].get<double>()
                                           : 0.0;
  if (lo && hi)
    return std::string("in ") + (s.contains("minimum") ? "[" : "(") + sim::format_number(min) + ", " +
           sim::format_number(s["maximum"].get<double>()) + "]";
  if (lo) return (s.contains("minimum") ? ">= " : "> ") + sim::format_number(min);
  if (hi) return "<= " + sim::format_number(s["maximum"].get<double>());
  return "";
}

/// Adds a "description" with unit, range and default to a recorded schema.
ojson describe_key(const std::string& object, const std::string& key, const json& recorded) {
  ojson s = ojson::parse(recorded.dump());
  std::string unit = s.contains("x-unit") ? s["x-unit"].get<std::string>() : unit_of(object, key);
  s.erase("x-unit");
  std::string text;
  if (recorded.contains("anyOf") && recorded.contains("x-unit"))
    text = "a number, or {\"mean\", \"deviation\"} (normal distribution, clamped to \"min\"/\"max\") or {\"min\", "
           "\"max\"} (uniform)";
  std::string range = range_text(recorded);
  if (range.empty() && recorded.contains("items")) range = range_text(recorded["items"]);
  if (range.empty() && recorded.contains("anyOf")) range = range_text(recorded["anyOf"][0]);
  auto add = [&text](const std::string& part) {
    if (!part.empty()) text += (text.empty() ? "" : "; ") + part;
  };
  if (!unit.empty()) add("unit: " + unit);
  if (!range.empty()) add((recorded.contains("items") ? "each " : "") + range);
  if (recorded.contains("default")) add("default " + recorded["default"].dump());
  if (!text.empty()) s["description"] = text;
  return s;
}

/// The schema of the object recorded at `pointer` and of its nested objects and arrays.
ojson object_schema(const KeyLog& log, const std::string& pointer) {
  ojson props = ojson::object();
  for (const auto& [object, keys] : log.objects()) {
    if (object != pointer) continue;
    for (const auto& [key, schemas] : keys) {
      const std::string child = pointer + "/" + pointer_token(key);
      const bool is_object = !log.keys(child).empty();
      const bool is_array = !log.keys(child + "/*").empty();
      if (is_object || is_array) {
        ojson nested = object_schema(log, is_object ? child : child + "/*");
        if (is_array) {
          ojson a = {{"type", "array"}, {"items", nested}};
          // An array of keys or a preset name (cloth pins): keep the other forms too.
          ojson any = ojson::array({a});
          for (const json& s : schemas)
            if (!s.empty()) any.push_back(describe_key(pointer, key, s));
          props[key] = any.size() == 1 ? a : ojson{{"anyOf", any}};
        } else {
          props[key] = nested;
        }
        continue;
      }
      if (schemas.size() == 1) {
        props[key] = describe_key(pointer, key, schemas.front());
      } else {
        ojson any = ojson::array();
        for (const json& s : schemas) any.push_back(describe_key(pointer, key, s));
        props[key] = {{"anyOf", any}};
      }
    }
  }
  return {{"type", "object"}, {"properties", props}, {"additionalProperties", false}};
}

ojson knob_schema(const effects::KnobSpec& k) {
  using effects::KnobType;
  ojson num = {{"type", k.type == KnobType::integer ? "integer" : "number"}};
  if (std::isfinite(k.min)) num["minimum"] = k.min;
  if (std::isfinite(k.max)) num["maximum"] = k.max;
  ojson s;
  switch (k.type) {
    case KnobType::number:
    case KnobType::integer: s = num; break;
    case KnobType::boolean: s = {{"type", "boolean"}}; break;
    case KnobType::vec2: s = {{"type", "array"}, {"items", num}, {"minItems", 2}, {"maxItems", 2}}; break;
    case KnobType::vec3:
      s = {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}};
      break;
    case KnobType::color:
      s = {{"type", "array"}, {"items", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}}}, {"minItems", 3},
           {"maxItems", 4}};
      break;
    case KnobType::choice: s = {{"enum", k.choices}}; break;
  }
  std::string text = k.description;
  if (!k.unit.empty()) text += " Unit: " + k.unit + ".";
  const std::string range = range_text(json::parse(s.contains("items") ? s["items"].dump() : s.dump()));
  if (!range.empty()) text += std::string(" Range: ") + (s.contains("items") ? "each " : "") + range + ".";
  text += " Default " + k.default_value.dump() + ".";
  s["default"] = ojson::parse(k.default_value.dump());
  s["description"] = text;
  return s;
}

/// An emitter given as an effect preset: {"effect", knobs..., "name", "overrides"}.
ojson effect_schema(const effects::EffectSpec& e) {
  ojson props = {{"effect", {{"const", e.name}, {"description", e.description + " (" + e.book + ")"}}},
                 {"name", {{"type", "string"}, {"description", "base name of the derived emitters; default \"" + e.name + "\""}}}};
  for (const auto& k : e.knobs) props[k.name] = knob_schema(k);
  props["overrides"] = {{"type", "object"},
                        {"description", "a JSON merge patch of the derived emitter (several: one patch per role); "
                                        "`simreel presets " + e.name + " --expand` prints them"}};
  return {{"type", "object"}, {"properties", props}, {"required", {"effect"}}, {"additionalProperties", false}};
}

}  // namespace

std::string scene_schema_text() {
  KeyLog log;
  {
    const KeyLog::Scope scope(log);
    try {
      scene_from_json(json::parse(kProbe), "probe.json");
    } catch (const SceneError&) {
      // The probe is not a valid scene (no mesh files); only the keys read count.
    }
  }
  ojson schema = {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
                  {"$id", "https://simreel.invalid/schema/scene-" SIMREEL_VERSION ".json"},
                  {"title", "simreel scene"},
                  {"description", "A simreel scene (README \"Scene format\"). Generated by `simreel schema` "
                                  "from the keys the loader reads; `simreel validate` has the last word."}};
  ojson root = object_schema(log, "");
  // Emitters: a low-level emitter, or an effect preset with its knobs.
  ojson emitter = root["properties"]["emitters"]["items"];
  ojson presets = ojson::array();
  for (const auto& e : effects::effect_specs()) presets.push_back(effect_schema(e));
  root["properties"]["emitters"]["items"] = {{"if", {{"type", "object"}, {"required", {"effect"}}}},
                                            {"then", {{"oneOf", presets}}},
                                            {"else", emitter}};
  for (auto it = root.begin(); it != root.end(); ++it) schema[it.key()] = it.value();
  return schema.dump(2) + "\n";
}

int schema_command(const std::string& output) {
  const std::string text = scene_schema_text();
  if (output.empty()) {
    std::cout << text;
    return 0;
  }
  check_outputs({{"-o", output, false}});
  render::write_file_atomic(output, text);
  std::cout << "wrote " << output << "\n";
  return 0;
}

}  // namespace simreel::app
