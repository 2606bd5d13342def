#include "model/effects/effect_library.hpp"

#include "model/effects/ei_profile.hpp"
#include "model/effects/ei_scale.hpp"
#include "model/effects/mesenteric_retraction.hpp"
#include "model/effects/sigmoid_mobility.hpp"
#include "model/effects/tissue_stiffening.hpp"
#include "model/effects/viscoadhesive_friction.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

using Reader = std::shared_ptr<const WorldEffect> (*)(const io::JsonObject&);

struct Entry {
    const char* name;
    Reader read;
};

constexpr Entry kEffects[] = {
    {ViscoadhesiveFriction::kName, &ViscoadhesiveFriction::read},
    {MesentericRetraction::kName, &MesentericRetraction::read},
    {EiProfile::kName, &EiProfile::read},
    {EiScale::kName, &EiScale::read},
    {SigmoidMobility::kName, &SigmoidMobility::read},
    {TissueStiffening::kName, &TissueStiffening::read},
};

std::string known_list() {
    std::string list;
    for (const Entry& e : kEffects)
        list += std::string(list.empty() ? "" : ", ") + e.name;
    return list;
}

}  // namespace

std::vector<std::string> world_effect_names() {
    std::vector<std::string> names;
    for (const Entry& e : kEffects)
        names.emplace_back(e.name);
    return names;
}

std::shared_ptr<const WorldEffect> make_world_effect(const nlohmann::json& spec,
                                                     const std::string& path) {
    const io::JsonObject o(spec, path);
    const std::string name = o.string("name");
    for (const Entry& e : kEffects)
        if (name == e.name) return e.read(o);
    throw ModelError(o.field("name") + ": unknown truth effect " + io::quote_text(name) +
                     " (known: " + known_list() + ")");
}

std::vector<std::shared_ptr<const WorldEffect>> read_world_effects(const nlohmann::json& list,
                                                                   const std::string& path) {
    if (!list.is_array())
        throw ModelError(path + ": expected an array of effects, got " +
                         std::string(list.type_name()));
    std::vector<std::shared_ptr<const WorldEffect>> effects;
    for (std::size_t i = 0; i < list.size(); ++i) {
        const std::string at = path + "[" + std::to_string(i) + "]";
        effects.push_back(make_world_effect(list[i], at));
        for (std::size_t j = 0; j + 1 < effects.size(); ++j)
            if (effects[j]->name() == effects.back()->name())
                throw ModelError(at + ".name: '" + effects.back()->name() +
                                 "' is already given in " + path + "[" + std::to_string(j) +
                                 "] (each effect at most once)");
    }
    return effects;
}

}  // namespace scopekin::model
