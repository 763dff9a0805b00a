// `simreel presets`: list the effect presets (Coutinho §3.9.1) and their knobs, or print one as a
// ready-to-paste emitter object.
#include <iomanip>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
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

}  // namespace

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
