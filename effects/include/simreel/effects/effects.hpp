#pragma once
/// @file effects.hpp
/// The specialised particle systems of Coutinho §3.9.1 as presets: a user names an effect and
/// sets a few physically meaningful knobs; the effect derives the emitters, forces, splitting,
/// colours and render style as low-level scene JSON, which the scene loader then reads like any
/// hand-written emitter (so every derived value can still be overridden).
///
/// Each effect's knobs, with types, defaults, ranges and units, are defined in
/// effects/presets/<effect>.json, compiled into the library.

#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace simreel::effects {

enum class KnobType {
  number,   ///< a real in [min, max]
  integer,  ///< an integer in [min, max]
  boolean,
  vec2,     ///< two numbers, each in [min, max]
  vec3,     ///< three numbers (a point or vector, world frame)
  color,    ///< linear RGB, each in [0, 1]
  choice,   ///< one of `choices`
};

/// One knob of an effect.
struct KnobSpec {
  std::string name;         ///< the JSON key, units in the name where not SI (`intensity_mm_h`)
  KnobType type = KnobType::number;
  nlohmann::json default_value;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  std::vector<std::string> choices;
  std::string unit;         ///< for `simreel presets` and the README
  std::string description;
};

struct EffectSpec {
  std::string name;
  std::string description;
  std::string book;  ///< the section of Coutinho the recipe follows
  std::vector<KnobSpec> knobs;
  [[nodiscard]] const KnobSpec* knob(std::string_view key) const;
};

/// Every effect, sorted by name (parsed once from the compiled-in preset files).
const std::vector<EffectSpec>& effect_specs();
/// nullptr if no effect has that name.
const EffectSpec* find_effect(std::string_view name);

/// What an effect expands to: low-level scene JSON, in the format of the scene file's
/// `emitters` and `force_fields` arrays (README "Scene format").
struct Derived {
  /// Emitter objects. Each has a "name" of `base_name` or `base_name/role` (e.g. "fire/core")
  /// and is tagged with its role in "role" (removed by the caller before parsing).
  nlohmann::json emitters = nlohmann::json::array();
  nlohmann::json force_fields = nlohmann::json::array();
};

/// Derives the low-level definition of `spec` for knob values `knobs` (an object holding every
/// knob of the effect, already checked against its spec; see complete_knobs()). `gravity_z` is
/// the scene's vertical gravity (m/s², < 0 for a normal world), `seed` the scene seed.
/// @throws std::invalid_argument if a knob is missing or has the wrong type (a caller bug).
Derived derive(const EffectSpec& spec, const nlohmann::json& knobs, const std::string& base_name,
               double gravity_z);

}  // namespace simreel::effects
