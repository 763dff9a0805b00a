#include "effect_scene.hpp"

#include <algorithm>

#include "scene_read.hpp"
#include "simreel/effects/effects.hpp"

namespace simreel::app {

namespace {

using effects::KnobType;

json read_knob(ObjectReader& r, const effects::KnobSpec& k) {
  const json& d = k.default_value;
  switch (k.type) {
    case KnobType::number: return r.number(k.name, d.get<double>(), k.min, k.max);
    case KnobType::integer: return r.integer(k.name, d.get<long long>(), (long long)k.min, (long long)k.max);
    case KnobType::boolean: return r.boolean(k.name, d.get<bool>());
    case KnobType::vec2: return r.numbers(k.name, d.get<std::vector<double>>(), 2, k.min, k.max);
    case KnobType::vec3: {
      const auto v = d.get<std::vector<double>>();
      const auto x = r.vec3(k.name, {v[0], v[1], v[2]});
      return json::array({x[0], x[1], x[2]});
    }
    case KnobType::color: {
      const auto v = d.get<std::vector<double>>();
      const auto c = r.color(k.name, {v[0], v[1], v[2], 1.0});
      return json::array({c[0], c[1], c[2]});
    }
    case KnobType::choice: return r.choice(k.name, d.get<std::string>(), k.choices);
  }
  return d;
}

/// The keys of a low-level emitter object, as its reader reads them.
const std::vector<std::string>& emitter_keys() {
  static const std::vector<std::string> keys = [] {
    KeyLog log;
    const KeyLog::Scope scope(log);
    std::vector<std::string> errors;
    scene_read::emitter(json::object(), "", "", errors, 0, sim::Vec3(0, 0, -9.81));
    return log.keys("");
  }();
  return keys;
}

/// The effect named `name`, or nullptr after reporting it with the closest effect's name.
const effects::EffectSpec* find_named_effect(const json& j, const std::string& ptr, const std::string& file,
                                             std::vector<std::string>& errors) {
  const json& value = j.at("effect");
  std::string names;
  for (const auto& e : effects::effect_specs()) names += (names.empty() ? "\"" : ", \"") + e.name + "\"";
  if (!value.is_string()) {
    errors.push_back(file + ": " + ptr + "/effect: expected one of " + names + ", found " + describe(value));
    return nullptr;
  }
  const std::string name = value.get<std::string>();
  if (const effects::EffectSpec* spec = effects::find_effect(name)) return spec;
  std::string closest;
  std::size_t best = std::string::npos;
  for (const auto& e : effects::effect_specs()) {
    const std::size_t d = edit_distance(name, e.name);
    if (d < best) {
      best = d;
      closest = e.name;
    }
  }
  std::string msg = file + ": " + ptr + "/effect: unknown effect \"" + name + "\"";
  if (best <= std::max<std::size_t>(2, closest.size() / 3)) msg += "; did you mean \"" + closest + "\"?";
  else msg += "; expected one of " + names;
  errors.push_back(msg + " (`simreel presets` lists them)");
  return nullptr;
}

/// The role names of an effect's derived emitters, in order, without repeats.
std::vector<std::string> effect_roles(const effects::EffectSpec& spec) {
  json knobs = json::object();
  for (const auto& k : spec.knobs) knobs[k.name] = k.default_value;
  std::vector<std::string> roles;
  for (const json& e : effects::derive(spec, knobs, spec.name, -9.81).emitters) {
    const std::string role = e.at("role").get<std::string>();
    if (std::find(roles.begin(), roles.end(), role) == roles.end()) roles.push_back(role);
  }
  return roles;
}

}  // namespace

EffectExpansion expand_effect(const json& j, const std::string& ptr, const std::string& file,
                              std::vector<std::string>& errors, double gravity_z) {
  EffectExpansion out;
  const effects::EffectSpec* spec = find_named_effect(j, ptr, file, errors);
  if (!spec) return out;  // reported, with the closest effect's name rather than another's knobs
  ObjectReader r(j, ptr, file, errors);
  r.known("effect");
  const std::string& name = spec->name;
  const std::string base = r.string("name", name);
  json knobs = json::object();
  for (const auto& k : spec->knobs) knobs[k.name] = read_knob(r, k);
  const json* overrides = r.get("overrides");
  if (overrides && !overrides->is_object()) {
    r.error("overrides", "an object (a JSON merge patch of the derived emitter)", *overrides);
    overrides = nullptr;
  }
  const std::size_t errors_before = errors.size();
  // A key of the derived emitters given beside the knobs belongs in "overrides".
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    if (r.has(key) && (spec->knob(key) || key == "effect" || key == "name" || key == "overrides")) continue;
    const auto& ek = emitter_keys();
    if (std::find(ek.begin(), ek.end(), key) == ek.end()) continue;
    r.known(key);
    const std::vector<std::string> roles = effect_roles(*spec);
    std::string where = "\"overrides\": {\"" + key + "\": " + it.value().dump() + "}";
    if (roles.size() > 1) {
      where = "\"overrides\": {\"" + roles.front() + "\": {\"" + key + "\": " + it.value().dump() +
              "}} (one patch per derived emitter:";
      for (const auto& role : roles) where += " " + role;
      where += ")";
    }
    errors.push_back(file + ": " + ptr + "/" + pointer_token(key) + ": \"" + key + "\" is a key of the emitter" +
                     (roles.size() > 1 ? "s" : "") + " the " + name +
                     " effect derives, not one of its knobs; expected it under " + where +
                     "; `simreel presets " + name + " --expand` prints them");
  }
  r.finish();
  if (errors.size() != errors_before) return out;  // unknown knob: do not derive from a typo

  effects::Derived d = effects::derive(*spec, knobs, base, gravity_z);
  const bool single = d.emitters.size() == 1;
  std::vector<std::string> roles;
  for (const json& e : d.emitters) roles.push_back(e.at("role").get<std::string>());
  if (overrides && !single) {
    for (auto it = overrides->begin(); it != overrides->end(); ++it) {
      bool found = false;
      for (const auto& role : roles) found = found || role == it.key();
      if (!found) {
        std::string msg = file + ": " + ptr + "/overrides/" + pointer_token(it.key()) + ": the " + name +
                          " effect derives several emitters; expected a role name (";
        for (std::size_t i = 0; i < roles.size(); ++i)
          if (std::find(roles.begin(), roles.begin() + std::ptrdiff_t(i), roles[i]) == roles.begin() + std::ptrdiff_t(i))
            msg += (i ? ", " : "") + roles[i];
        errors.push_back(msg + ") holding a patch, found \"" + it.key() + "\"");
      } else if (!it.value().is_object()) {
        errors.push_back(file + ": " + ptr + "/overrides/" + pointer_token(it.key()) +
                         ": expected an object (a patch of that emitter), found " + describe(it.value()));
      }
    }
  }
  for (json& e : d.emitters) {
    const std::string role = e.at("role").get<std::string>();
    e.erase("role");
    std::string where = ptr + "/overrides";
    if (overrides && single) {
      e.merge_patch(*overrides);
    } else if (overrides && overrides->contains(role) && overrides->at(role).is_object()) {
      e.merge_patch(overrides->at(role));
      where += "/" + pointer_token(role);
    }
    out.emitters.push_back({std::move(e), where});
  }
  out.force_fields = std::move(d.force_fields);
  return out;
}

}  // namespace simreel::app
