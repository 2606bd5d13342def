// fuzz_scenario.cpp — libFuzzer target: reading a scenario or model file (model/scenario/
// scenario.hpp: parse_json_text, then read_scenario and read_world_model, then scene_effects),
// as `scopekin simulate` and `scopekin discrepancy` do before they build a world.  The world is
// not built or run (seconds per input): the target stops at the validated Scenario.
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * a refusal is a ModelError (no other exception: no nlohmann, std::out_of_range or
//     bad_alloc escapes), its message starts with "fuzz.json" and is at most 1,000 characters;
//   * read_scenario and read_world_model agree where they overlap: a document read_scenario
//     accepts, read_world_model accepts unless it is a free beam scenario (it reads worlds only);
//   * accepted: the document serialised and read again gives a scenario of the same kind,
//     description, scope, procedure length and output settings; scene_effects() builds.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_support.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"
#include "model/scenario/scenario.hpp"

namespace {

namespace model = scopekin::model;
using nlohmann::json;

void require_model_error_text(const model::ModelError& error) {
    const std::string message = error.what();
    require(message.rfind("fuzz.json", 0) == 0);
    require(message.size() <= 1000U);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    json document;
    try {
        document = model::io::parse_json_text(text, "fuzz.json");
    } catch (const model::ModelError& error) {
        require_model_error_text(error);
        return 0;
    } catch (...) {
        require(false);
    }

    bool world_model_ok = false;
    try {
        (void)model::read_world_model(document, "fuzz.json");
        world_model_ok = true;
    } catch (const model::ModelError& error) {
        require_model_error_text(error);
    } catch (...) {
        require(false);
    }

    model::Scenario scenario;
    try {
        scenario = model::read_scenario(document, "fuzz.json");
    } catch (const model::ModelError& error) {
        require_model_error_text(error);
        return 0;
    } catch (...) {
        require(false);
    }
    if (scenario.kind == model::ScenarioKind::world) require(world_model_ok);

    model::Scenario again;
    try {
        again = model::read_scenario(json::parse(document.dump()), "fuzz.json");
        (void)model::scene_effects(scenario);
    } catch (...) {
        require(false);
    }
    require(again.kind == scenario.kind);
    require(again.description == scenario.description);
    require(again.scope_model == scenario.scope_model);
    require(again.procedure.actions().size() == scenario.procedure.actions().size());
    require(again.procedure.end_s() == scenario.procedure.end_s());
    require(again.outputs.sample_rate_Hz == scenario.outputs.sample_rate_Hz);
    require(again.outputs.nodes_from_tip_mm == scenario.outputs.nodes_from_tip_mm);
    require(again.effects.size() == scenario.effects.size());
    require(again.colon.has_value() == scenario.colon.has_value());
    require(again.beam_problem.has_value() == scenario.beam_problem.has_value());
    return 0;
}
