#include "host_sim/discrepancy/model_spec.hpp"

#include <utility>

#include "model/effects/effect_library.hpp"

namespace scopekin::discrepancy {

nlohmann::json default_model() {
    return nlohmann::json::parse(R"({
    "description": "The default model: CF-Q160L in the bundled default colon, as the firmware's reduced model was built from it",
    "colon": {"bundled": "default"},
    "scope": {"model": "cf_q160l", "length_mm": 1700, "elements": 170},
    "gravity_mm_per_s2": [0, 0, -9810],
    "solver": {"time_step_s": 0.01}
  })");
}

ModelSpec read_model_spec(nlohmann::json document, const std::string& source) {
    ModelSpec spec;
    spec.source = source;
    spec.scenario = model::read_world_model(document, source);
    if (document.contains("truth_effects")) spec.truth_effects = document["truth_effects"];
    spec.document = std::move(document);
    return spec;
}

model::Scenario scenario_for_run(const ModelSpec& model, const nlohmann::json& extra_effects,
                                 double initial_insertion_mm) {
    model::Scenario scenario = model.scenario;
    model::set_initial_insertion(scenario, initial_insertion_mm);
    nlohmann::json entries = model.truth_effects;
    for (const auto& e : extra_effects)
        entries.push_back(e);
    if (!entries.empty())
        scenario.effects = model::read_world_effects(entries, model.source + ": truth_effects");
    for (auto& e : model::scene_effects(scenario))
        scenario.effects.push_back(std::move(e));
    return scenario;
}

nlohmann::json with_effects(const ModelSpec& model, const nlohmann::json& effects) {
    nlohmann::json document = model.document;
    nlohmann::json all =
        document.contains("truth_effects") ? document["truth_effects"] : nlohmann::json::array();
    for (const auto& e : effects)
        all.push_back(e);
    document["truth_effects"] = all;
    return document;
}

}  // namespace scopekin::discrepancy
