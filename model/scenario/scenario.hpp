#pragma once
// Scenario files (model/scenario/README.md): what `scopekin simulate` runs. Two kinds, told apart
// by their top-level keys:
//  * a world scenario ("colon", or "patient": a drawn or saved virtual patient, model/patient/):
//    a colon, a scope, solver settings, a procedure at the handle (scripted, or a "physician"
//    who reacts to the world, model/physician/) and the outputs wanted;
//  * a free beam scenario ("beam"): exactly a beam problem file (model/io/beam_problem.hpp),
//    solved statically.
// Read strictly: unknown keys, wrong types and unphysical values are rejected with the field's
// full path (ModelError).
#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "model/colon/colon_region.hpp"
#include "model/colon/colon_tube.hpp"
#include "model/io/beam_problem.hpp"
#include "model/patient/patient.hpp"
#include "model/physician/physician.hpp"
#include "model/scenario/abdominal_pressure.hpp"
#include "model/scenario/hand_command_source.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/tip_steering.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

enum class ScenarioKind {
    world,
    free_beam
};

struct ScenarioOutputs {
    double sample_rate_Hz = 30.0;           ///< rows of the recording (the thesis's sensor rate)
    std::vector<double> nodes_from_tip_mm;  ///< extra node position columns (nearest node)
    bool contacts_file = false;             ///< also write one row per loaded contact per sample
};

struct Scenario {
    ScenarioKind kind = ScenarioKind::world;
    std::string source;  ///< the file name (or what the caller named the document)
    std::string description;

    // World scenario.
    std::optional<ColonTube> colon;
    /// "patient": the virtual patient the colon, its regions, the friction coefficient and the
    /// scope's EI profile come from (instead of "colon", "colon_regions" and
    /// solver.contact.friction_coefficient); empty for a scenario with "colon".
    std::optional<PatientSpec> patient;
    std::array<ColonRegionProperties, 8> colon_properties{};  ///< kColonRegionsInOrder order
    std::string scope_model = "cf_q160l";
    ScopeSpec scope;
    WorldSettings settings;
    /// "procedure": the hand's scripted timeline (empty with a physician).
    Procedure procedure;
    /// "physician": a procedure generator that reacts to the world (model/physician/), instead
    /// of "procedure"; it switches the tip steering and the abdominal pressure itself, through
    /// `scene_control` (read by the TipSteering and AbdominalPressure in `effects`).
    std::optional<PhysicianSpec> physician;
    std::shared_ptr<SceneControl> scene_control;
    ScenarioOutputs outputs;
    /// "truth_effects": physical effects the firmware's model lacks (model/effects/EFFECTS.md),
    /// passed to the World by build_world. Empty = none.
    std::vector<std::shared_ptr<const WorldEffect>> effects;
    /// "steering": when the physician steers the tip down the lumen (model/scenario/tip_steering.hpp);
    /// added to `effects` as a TipSteering.
    std::vector<SteeringWindow> steering;
    /// "abdominal_pressure": when and where the assistant presses on the abdomen
    /// (model/scenario/abdominal_pressure.hpp); added to `effects` as an AbdominalPressure.
    std::vector<AbdominalPressureWindow> abdominal_pressure;
    /// "sensors": the host simulator's sensor models (host_sim/sensors/SENSORS.md), read there.
    nlohmann::json sensors = nlohmann::json::object();
    std::string sensors_path = "sensors";

    // Free beam scenario.
    std::optional<io::BeamProblem> beam_problem;
};

/// Reads and validates a scenario document; `source` names it in messages.
Scenario read_scenario(const nlohmann::json& document, const std::string& source);
/// Reads a world model: a world scenario's document without its run. "procedure", "physician" and
/// "initial_insertion_mm" are not read (whoever runs the model gives them: `scopekin discrepancy`
/// drives it with a recording); every other key is read and checked as read_scenario does.
/// Scenario::effects is left empty: a run makes its own instances (read_world_effects of the
/// truth_effects entries, then scene_effects), as an effect may keep state over a run.
Scenario read_world_model(const nlohmann::json& document, const std::string& source);
/// Where the scope starts: "initial_insertion_mm" given by the runner (ModelError, naming the
/// field under the scenario's source, if negative or not shorter than the scope).
void set_initial_insertion(Scenario& scenario, double initial_insertion_mm);
/// New instances of the effects the scenario's patient (its scope's "ei_profile"), "steering" and
/// "abdominal_pressure" windows add (in that order, after the truth effects); none for an absent
/// patient or an empty list, which act on nothing. (A world model has no physician.)
std::vector<std::shared_ptr<const WorldEffect>> scene_effects(const Scenario& scenario);
/// Reads a scenario file. A key "model": "FILE" (relative to the scenario file; e.g. the model.json
/// of `scopekin discrepancy`) takes every key from that model file that the scenario does not
/// give itself; truth_effects are joined (the model's first).
Scenario read_scenario_file(const std::string& filename);
/// The document with its "model" file merged in (as read_scenario_file does).
nlohmann::json with_model_file(nlohmann::json document, const std::string& filename);

/// Scope node nearest to `arc_from_tip_mm` on a uniform scope of `elements` elements.
std::size_t scope_node_from_tip(double arc_from_tip_mm, double scope_length_mm,
                                std::size_t elements);

}  // namespace scopekin::model
