#pragma once
// The model the discrepancy workflow tests (host_sim/discrepancy/README.md): a world scenario
// without its run, read and checked once (model::read_world_model). The recording gives the run:
// the scope's first insertion and the hand's motion (model_run.hpp). The truth effects stay
// entries of the effect library (model/effects/EFFECTS.md), as the candidates' fitted effects
// are: every run makes its own instances of both, since an effect may keep state over a run.
#include <string>

#include <nlohmann/json.hpp>

#include "model/scenario/scenario.hpp"

namespace scopekin::discrepancy {

struct ModelSpec {
    std::string source;        ///< names it in messages and the report
    nlohmann::json document;   ///< as given: model.json is written from it
    model::Scenario scenario;  ///< read from it: no procedure, no effects
    nlohmann::json truth_effects = nlohmann::json::array();  ///< its own effects' entries
};

/// Reads and checks a model document; throws model::ModelError naming the field under `source`.
ModelSpec read_model_spec(nlohmann::json document, const std::string& source);

/// The scenario of one run: the model with its truth effects and then `extra_effects` (entries),
/// then the steering and abdominal pressure it has (the order of a scenario file), the scope
/// starting at `initial_insertion_mm`. Throws model::ModelError for a bad effect entry.
model::Scenario scenario_for_run(const ModelSpec& model, const nlohmann::json& extra_effects,
                                 double initial_insertion_mm);

/// model.json: the document as given with `effects` appended to its truth_effects.
nlohmann::json with_effects(const ModelSpec& model, const nlohmann::json& effects);

/// The default model: the bundled default colon and the CF-Q160L as the firmware's model has
/// them (h = 10 ms), no truth effects.
nlohmann::json default_model();

}  // namespace scopekin::discrepancy
