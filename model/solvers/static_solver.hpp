#pragma once
// Static equilibrium f_int(q) = lambda f_ext by Newton's method with load stepping.
// The load factor lambda goes from 0 to 1 in steps; a step whose Newton iteration does not
// converge is undone and halved (up to max_halvings times). Prescribed supports move to their
// targets in proportion to lambda.
#include <string>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/scope_beam.hpp"

namespace scopekin::model {

struct StaticSettings {
    int load_steps = 10;               ///< initial number of equal load steps
    int max_iterations = 30;           ///< Newton iterations per load step
    int max_halvings = 12;             ///< step halvings before giving up
    double relative_tolerance = 1e-9;  ///< residual / (|f_ext| + reaction scale)
    double absolute_force_tolerance_N = 1e-10;
};

struct LoadStepLog {
    double load_factor = 0;
    int iterations = 0;
    double residual_force_N = 0;
    double residual_moment_Nmm = 0;
    bool converged = false;
};

struct StaticReport {
    bool converged = false;
    int total_iterations = 0;
    std::vector<LoadStepLog> steps;  ///< every attempted step, including the halved-away ones
    std::string message;
    /// One line per accepted step: load factor, Newton iterations, final residuals.
    std::string convergence_table() const;
};

/// Solves in place from the beam's current pose. Throws ModelError for invalid loads or
/// supports; a non-converged solve returns converged = false with the reason in message and
/// leaves the beam at the last converged load step.
StaticReport solve_static(ScopeBeam& beam, const BeamLoads& loads,
                          const std::vector<NodeSupport>& supports,
                          const StaticSettings& settings = {});

}  // namespace scopekin::model
