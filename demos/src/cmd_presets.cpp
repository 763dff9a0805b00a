// `simreel presets`: list the effect presets (Coutinho §3.9.1) and their knobs, or print one as a
// ready-to-paste emitter object.
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "effect_scene.hpp"
#include "simreel/effects/effects.hpp"

namespace simreel::app {

namespace {

using effects::KnobType;

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

/// Indented JSON with arrays of numbers (points, colours) kept on one line.
void dump_compact(std::ostream& out, const nlohmann::ordered_json& v, int indent) {
  const std::string pad(std::size_t(indent) + 2, ' ');
  const bool flat = v.is_array() && std::all_of(v.begin(), v.end(), [](const auto& e) { return e.is_primitive(); });
  if (v.is_object() && !v.empty()) {
    out << "{\n";
    std::size_t i = 0;
    for (auto it = v.begin(); it != v.end(); ++it, ++i) {
      out << pad << nlohmann::json(it.key()).dump() << ": ";
      dump_compact(out, it.value(), indent + 2);
      out << (i + 1 < v.size() ? ",\n" : "\n");
    }
    out << std::string(std::size_t(indent), ' ') << "}";
  } else if (v.is_array() && !v.empty() && !flat) {
    out << "[\n";
    for (std::size_t i = 0; i < v.size(); ++i) {
      out << pad;
      dump_compact(out, v[i], indent + 2);
      out << (i + 1 < v.size() ? ",\n" : "\n");
    }
    out << std::string(std::size_t(indent), ' ') << "]";
  } else if (flat && !v.empty()) {
    out << "[";
    for (std::size_t i = 0; i < v.size(); ++i) out << (i ? ", " : "") << v[i].dump();
    out << "]";
  } else {
    out << v.dump();
  }
}

/// `presets EFFECT --expand [--set knob=value ...]`: the derived emitters and force fields as a
/// scene fragment, read (and checked) exactly as a scene's preset object would be.
int expand_command(const std::string& effect, const std::vector<std::string>& sets) {
  if (effect.empty()) throw SceneError("--expand: expected an effect name, e.g. simreel presets smoke --expand");
  json object = {{"effect", effect}};
  for (const std::string& set : sets) {
    const auto eq = set.find('=');
    std::string knob = eq == std::string::npos ? "" : set.substr(0, eq);
    if (!knob.empty() && knob.front() == '/') knob.erase(0, 1);
    if (knob.empty()) throw SceneError("--set " + set + ": expected KNOB=VALUE, e.g. --set rate_scale=2");
    const std::string text = set.substr(eq + 1);
    try {
      object[knob] = json::parse(text);
    } catch (const json::exception&) {
      object[knob] = text;  // a bare word is a string
    }
  }
  std::vector<std::string> errors;
  const EffectExpansion x = expand_effect(object, "", "presets " + effect + " --set", errors, -9.81);
  if (!errors.empty()) throw SceneError(errors);
  nlohmann::ordered_json out;
  out["emitters"] = nlohmann::ordered_json::array();
  // Through text: the derived JSON is unordered, the output keeps "emitters" first.
  for (const auto& e : x.emitters) out["emitters"].push_back(nlohmann::ordered_json::parse(e.object.dump()));
  if (!x.force_fields.empty()) out["force_fields"] = nlohmann::ordered_json::parse(x.force_fields.dump());
  dump_compact(std::cout, out, 0);
  std::cout << "\n";
  return 0;
}

}  // namespace

int presets_command(const std::string& effect, bool as_json, bool expand, const std::vector<std::string>& sets) {
  const auto& specs = effects::effect_specs();
  if (!effect.empty() && !effects::find_effect(effect)) {
    std::vector<std::string> errors;
    expand_effect({{"effect", effect}}, "", "presets", errors, -9.81);  // names the closest effect
    for (const auto& e : errors) std::cerr << "simreel: error: " << e.substr(std::string("presets: /effect: ").size()) << "\n";
    return 2;
  }
  if (!sets.empty() && !expand) throw SceneError("--set: expected --expand with it (presets EFFECT --expand --set KNOB=VALUE)");
  if (expand) return expand_command(effect, sets);
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
