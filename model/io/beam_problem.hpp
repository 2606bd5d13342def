#pragma once
// A static beam problem read from a JSON file: a free scope (or any beam) with its section,
// loads and supports, and no colon. Schema: model/README.md, section "Beam problem files".
// Unknown keys, wrong types and unphysical values are rejected with the field's path.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/scope_beam.hpp"
#include "model/solvers/static_solver.hpp"

namespace scopekin::model::io {

struct BeamProblem {
    ScopeBeam beam;
    BeamLoads loads;
    std::vector<NodeSupport> supports;
    StaticSettings settings;
    std::vector<std::size_t> output_nodes;  ///< nodes reported in the result (default: all)
};

/// Reads and validates; `source` names the file in messages.
BeamProblem read_beam_problem(const nlohmann::json& document, const std::string& source);
BeamProblem read_beam_problem_file(const std::string& filename);

}  // namespace scopekin::model::io
