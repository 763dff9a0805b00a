#pragma once
/// @file effect_scene.hpp
/// Emitters given as an effect preset in a scene: `{"effect": "rain", <knobs>, "name",
/// "overrides"}` -> checked knobs -> the effect's low-level emitters and force fields
/// (simreel::effects::derive) -> the overrides applied as a JSON merge patch (RFC 7386).

#include <cstddef>
#include <string>
#include <vector>

#include "json_reader.hpp"

namespace simreel::app {

struct ExpandedEmitter {
  json object;          ///< a low-level emitter object, read like a hand-written one
  std::string pointer;  ///< where errors in it are reported: the overrides that shaped it
};

struct EffectExpansion {
  std::vector<ExpandedEmitter> emitters;
  json force_fields = json::array();  ///< low-level force-field objects
};

/// Expands the emitter object `j` at `ptr` (it has an "effect" key). Knob errors (unknown effect,
/// unknown knob with a did-you-mean, wrong type, out of range) are appended to `errors` with the
/// file and pointer. With one derived emitter, "overrides" patches it; with several, its keys
/// are role names (e.g. "smoke", "core") each holding a patch. `gravity_z` (m/s²) is the
/// scene's vertical gravity.
EffectExpansion expand_effect(const json& j, const std::string& ptr, const std::string& file,
                              std::vector<std::string>& errors, double gravity_z);

}  // namespace simreel::app
