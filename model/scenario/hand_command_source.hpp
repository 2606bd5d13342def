#pragma once
// Where a run's hand commands come from. run_simulation (simulation.hpp) is the one stepping loop
// for every world run; what the hand does at each step is asked of a source: the procedure's
// player (procedure.hpp) for a scenario, or a recording's encoder for `scopekin discrepancy`
// (host_sim/discrepancy/model_run.hpp).
#include <cstddef>
#include <string>
#include <vector>

#include "model/world/world.hpp"

namespace scopekin::model {

class HandCommandSource {
public:
    virtual ~HandCommandSource() = default;
    /// The command for world step `step` (the step that takes the world from step - 1 to step,
    /// from world time t_s to t_s + h_s). `depth_now_mm` and `roll_now_rad` are the world's at t_s.
    virtual HandleCommand command_for_step(std::size_t step, double t_s, double h_s,
                                           double depth_now_mm, double roll_now_rad) = 0;
    /// What the source noticed while playing (SimulationSummary::warnings).
    virtual std::vector<std::string> warnings() const { return {}; }
};

}  // namespace scopekin::model
