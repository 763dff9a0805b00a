#include "effect_scene.hpp"

#include <algorithm>

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

}  // namespace

EffectExpansion expand_effect(const json& j, const std::string& ptr, const std::string& file,
                              std::vector<std::string>& errors, double gravity_z) {
  EffectExpansion out;
  ObjectReader r(j, ptr, file, errors);
  std::vector<std::string> names;
  for (const auto& e : effects::effect_specs()) names.push_back(e.name);
  const std::string name = r.choice("effect", names.front(), names);
  const effects::EffectSpec* spec = effects::find_effect(name);
  if (!spec) return out;  // reported by choice()
  const std::string base = r.string("name", name);
  json knobs = json::object();
  for (const auto& k : spec->knobs) knobs[k.name] = read_knob(r, k);
  const json* overrides = r.get("overrides");
  if (overrides && !overrides->is_object()) {
    r.error("overrides", "an object (a JSON merge patch of the derived emitter)", *overrides);
    overrides = nullptr;
  }
  const std::size_t errors_before = errors.size();
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
