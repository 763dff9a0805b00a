#include "effect_scene.hpp"

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <sstream>

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

std::string type_name(KnobType t) {
  switch (t) {
    case KnobType::number: return "number";
    case KnobType::integer: return "integer";
    case KnobType::boolean: return "boolean";
    case KnobType::vec2: return "[x, y]";
    case KnobType::vec3: return "[x, y, z]";
    case KnobType::color: return "[r, g, b]";
    case KnobType::choice: return "choice";
  }
  return "value";
}

std::string range_text(const effects::KnobSpec& k) {
  std::ostringstream s;
  if (k.type == KnobType::choice) {
    for (std::size_t i = 0; i < k.choices.size(); ++i) s << (i ? "|" : "") << k.choices[i];
  } else if (k.type == KnobType::number || k.type == KnobType::integer || k.type == KnobType::vec2) {
    s << k.min << " .. " << k.max;
  }
  return s.str();
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

int presets_command(const std::string& effect, bool as_json) {
  const auto& specs = effects::effect_specs();
  if (!effect.empty() && !effects::find_effect(effect)) {
    std::cerr << "simreel: error: unknown effect \"" << effect << "\"; expected one of:";
    for (const auto& e : specs) std::cerr << " " << e.name;
    std::cerr << "\n";
    return 2;
  }
  for (const auto& e : specs) {
    if (!effect.empty() && e.name != effect) continue;
    if (as_json) {
      nlohmann::ordered_json o;
      o["effect"] = e.name;
      o["name"] = e.name;
      for (const auto& k : e.knobs) o[k.name] = k.default_value;
      o["overrides"] = nlohmann::ordered_json::object();
      std::cout << o.dump(2) << "\n";
      continue;
    }
    std::cout << e.name << " — " << e.book << "\n  " << e.description << "\n";
    for (const auto& k : e.knobs) {
      std::cout << "    " << std::left << std::setw(18) << k.name << std::setw(10) << type_name(k.type)
                << " default " << std::setw(14) << k.default_value.dump();
      const std::string range = range_text(k);
      if (!range.empty()) std::cout << " range " << range;
      if (!k.unit.empty()) std::cout << " (" << k.unit << ")";
      std::cout << "\n      " << k.description << "\n";
    }
    std::cout << "\n";
  }
  return 0;
}

}  // namespace simreel::app
