#pragma once
// Implicit dynamics of the beam, M(q) a + C v + f_int(q) = f_ext (thesis Eq. 4.1), integrated
// with the backward (implicit) Euler scheme:
//   v_{n+1} = d / h,   M (v_{n+1} - v_n) / h + C v_{n+1} + f_int(q_n + d) = f_ext(t_{n+1}),
// solved for the step increment d by Newton with the matrix  M/h^2 + C/h + K_T.
// Why backward Euler: it is the scheme behind the thesis's Delassus operator
// W = (M/h^2 + C/h + K)^-1 (Eq. 4.20, as in SOFA's EulerImplicit), it is unconditionally stable
// for h = 1 ms ... 33 ms, and its numerical damping of the stiff high modes is welcome in contact.
// Its price: first-order accuracy, extra damping of the resolved low modes (about w h / 2).
// M and C are evaluated at the start of each step (the "updated" matrices of Eq. 4.1);
// C = a' M + b' K_material uses the positive semi-definite material tangent.
#include <Eigen/Dense>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/scope_beam.hpp"
#include "model/solvers/rayleigh_damping.hpp"

namespace scopekin::model {

struct DynamicSettings {
    double time_step_s = 0.005;  ///< allowed range [0.001, 0.033] s
    RayleighDamping damping = RayleighDamping::thesis_cf_q160l();
    int max_iterations = 20;
    double relative_tolerance = 1e-8;
    void validate() const;  ///< throws ModelError naming the field
};

struct DynamicStepReport {
    bool converged = false;
    int iterations = 0;
    double residual_force_N = 0;
};

class DynamicSolver {
public:
    DynamicSolver(const ScopeBeam& beam, DynamicSettings settings);
    /// Advances the beam by one time step. `loads` are evaluated at the end of the step;
    /// supports with targets are driven to those targets at the end of the step. Newton starts
    /// from a constant-velocity predictor with one factorisation per step (modified Newton) and
    /// falls back to plain Newton from q_n if that fails; a step that still fails to converge
    /// is undone (state and time unchanged) and reported with converged = false.
    DynamicStepReport step(ScopeBeam& beam, const BeamLoads& loads,
                           const std::vector<NodeSupport>& supports);
    /// Node velocities: 6 per node [mm/s, rad/s].
    const Eigen::VectorXd& velocity() const { return velocity_; }
    double time_s() const { return time_s_; }
    const DynamicSettings& settings() const { return settings_; }

private:
    DynamicStepReport attempt(ScopeBeam& beam, const BeamLoads& loads,
                              const std::vector<NodeSupport>& supports, bool fast);

    DynamicSettings settings_;
    Eigen::VectorXd velocity_;
    Eigen::VectorXd step_increment_;
    double time_s_ = 0;
    ScopeBeam::Assembly assembly_;
    BlockTridiagonalMatrix mass_, damping_, system_;
};

}  // namespace scopekin::model
