#pragma once
// The library of truth effects (model/effects/EFFECTS.md): physical effects the firmware's model
// does not have, switched on per scenario ("truth_effects" in a scenario file) with parameters.
// Each is a WorldEffect; this is where they are made from JSON, strictly: an unknown name or key,
// a wrong type or an out-of-range value is a ModelError naming the field ("<path>.<key>: ...").
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/world/world_effect.hpp"

namespace scopekin::model {

/// The effects' identifiers, in EFFECTS.md order: viscoadhesive_friction, mesenteric_retraction,
/// ei_profile, ei_scale, sigmoid_mobility, tissue_stiffening.
std::vector<std::string> world_effect_names();

/// One effect from {"name": "<identifier>", <parameters>} (every parameter optional: EFFECTS.md
/// gives the defaults). `path` names the object in messages, e.g. "s.json: truth_effects[0]".
std::shared_ptr<const WorldEffect> make_world_effect(const nlohmann::json& spec,
                                                     const std::string& path);

/// A list of effects ([{...}, ...]); `path` names the list. Each name at most once.
std::vector<std::shared_ptr<const WorldEffect>> read_world_effects(const nlohmann::json& list,
                                                                   const std::string& path);

}  // namespace scopekin::model
