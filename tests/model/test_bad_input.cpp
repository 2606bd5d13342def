// Malformed or unphysical input is a ModelError whose message names the offending field
// (model/model_error.hpp), never a crash, a NaN result or a silent default.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/scope_beam.hpp"
#include "model/modal/planar_modes.hpp"
#include "model/model_error.hpp"
#include "model/solvers/dynamic_solver.hpp"
#include "model/solvers/static_solver.hpp"

namespace scopekin::model {
namespace {

using Vec3 = Eigen::Vector3d;

BeamSection good_section() {
    return BeamSection{.axial_stiffness_N = 3000.0,
                       .bending_stiffness_y_Nmm2 = 35000.0,
                       .bending_stiffness_z_Nmm2 = 35000.0,
                       .torsional_stiffness_Nmm2 = 7000.0,
                       .shear_stiffness_y_N = 285.0,
                       .shear_stiffness_z_N = 285.0,
                       .mass_per_length_t_per_mm = 1.2e-6};
}

std::vector<Vec3> three_nodes() {
    return {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(20, 0, 0)};
}

/// Runs `f`, expects a ModelError whose message contains every one of `fragments`.
void expect_model_error(const std::function<void()>& f, const std::vector<std::string>& fragments) {
    try {
        f();
        ADD_FAILURE() << "no ModelError; expected one mentioning '" << fragments.front() << "'";
    } catch (const ModelError& e) {
        const std::string message = e.what();
        for (const std::string& fragment : fragments)
            EXPECT_NE(message.find(fragment), std::string::npos)
                << "message '" << message << "' lacks '" << fragment << "'";
    }
}

TEST(BadInput, ZeroLengthElementIsNamed) {
    expect_model_error(
        [] {
            ScopeBeam({Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(10, 0, 0)}, {good_section()});
        },
        {"element 1", "length"});
}

TEST(BadInput, NegativeOrNanSectionValuesAreNamed) {
    BeamSection negative_ei = good_section();
    negative_ei.bending_stiffness_z_Nmm2 = -35000.0;
    expect_model_error([&] { ScopeBeam(three_nodes(), {negative_ei}); },
                       {"bending_stiffness", "element 0"});

    BeamSection nan_shear = good_section();
    nan_shear.shear_stiffness_y_N = std::nan("");
    expect_model_error([&] { ScopeBeam(three_nodes(), {nan_shear}); }, {"shear_stiffness_y_N"});

    BeamSection zero_ea = good_section();
    zero_ea.axial_stiffness_N = 0.0;
    expect_model_error([&] { ScopeBeam(three_nodes(), {zero_ea}); }, {"axial_stiffness_N"});

    BeamSection negative_mass = good_section();
    negative_mass.mass_per_length_t_per_mm = -1e-6;
    expect_model_error([&] { ScopeBeam(three_nodes(), {negative_mass}); }, {"mass_per_length"});

    // The second of two per-element sections is reported as element 1.
    BeamSection bad_gj = good_section();
    bad_gj.torsional_stiffness_Nmm2 = std::numeric_limits<double>::infinity();
    expect_model_error(
        [&] {
            ScopeBeam(three_nodes(), {good_section(), bad_gj});
        },
        {"element 1", "torsional"});

    // Infinite shear stiffness is allowed (Euler-Bernoulli limit).
    BeamSection euler_bernoulli = good_section();
    euler_bernoulli.shear_stiffness_y_N = euler_bernoulli.shear_stiffness_z_N =
        std::numeric_limits<double>::infinity();
    EXPECT_NO_THROW(ScopeBeam(three_nodes(), {euler_bernoulli}));
}

TEST(BadInput, NonFiniteCoordinateIsNamed) {
    std::vector<Vec3> nodes = three_nodes();
    nodes.push_back(Vec3(30, 0, 0));
    nodes[2].y() = std::nan("");
    expect_model_error([&] { ScopeBeam(nodes, {good_section()}); }, {"node 2 coordinate", "y"});
    nodes[2].y() = 0.0;
    nodes[3].z() = std::numeric_limits<double>::infinity();
    expect_model_error([&] { ScopeBeam(nodes, {good_section()}); }, {"node 3 coordinate", "z"});
}

TEST(BadInput, FewerThanTwoNodesIsRejected) {
    expect_model_error([] { ScopeBeam({Vec3(0, 0, 0)}, {good_section()}); },
                       {"nodes", "at least 2"});
    expect_model_error([] { ScopeBeam({}, {good_section()}); }, {"nodes"});
}

TEST(BadInput, WrongNumberOfSectionsIsRejected) {
    expect_model_error(
        [] {
            ScopeBeam(three_nodes(), {good_section(), good_section(), good_section()});
        },
        {"sections"});
    expect_model_error([] { ScopeBeam(three_nodes(), {}); }, {"sections"});
}

TEST(BadInput, LoadOnAnOutOfRangeNodeIsNamed) {
    ScopeBeam beam(three_nodes(), {good_section()});
    BeamLoads loads;
    loads.nodal.push_back({3, Vec3(0, 1, 0), Vec3::Zero()});  // nodes are 0..2
    NodeSupport clamp;
    expect_model_error([&] { solve_static(beam, loads, {clamp}); }, {"loads[0].node"});
    DynamicSolver dynamic(beam, DynamicSettings{});
    expect_model_error([&] { dynamic.step(beam, loads, {clamp}); }, {"loads[0].node"});
}

TEST(BadInput, NonFiniteLoadIsNamed) {
    ScopeBeam beam(three_nodes(), {good_section()});
    NodeSupport clamp;
    BeamLoads loads;
    loads.nodal.push_back({2, Vec3(0, 1, 0), Vec3::Zero()});
    loads.nodal.push_back({1, Vec3(0, std::nan(""), 0), Vec3::Zero()});
    expect_model_error([&] { solve_static(beam, loads, {clamp}); }, {"loads[1].force_N"});
    BeamLoads gravity;
    gravity.gravity_mm_per_s2.z() = std::numeric_limits<double>::infinity();
    expect_model_error([&] { solve_static(beam, gravity, {clamp}); }, {"gravity"});
}

TEST(BadInput, SupportOnAnOutOfRangeNodeIsNamed) {
    ScopeBeam beam(three_nodes(), {good_section()});
    NodeSupport clamp, outside;
    outside.node = 7;
    expect_model_error(
        [&] {
            solve_static(beam, BeamLoads{}, {clamp, outside});
        },
        {"supports[1].node", "7"});
}

TEST(BadInput, NodeSupportedTwiceIsNamed) {
    ScopeBeam beam(three_nodes(), {good_section()});
    NodeSupport first, second;
    first.node = second.node = 1;
    expect_model_error(
        [&] {
            solve_static(beam, BeamLoads{}, {first, second});
        },
        {"supports[1].node", "twice"});
}

TEST(BadInput, TargetThatIsNotARotationIsNamed) {
    ScopeBeam beam(three_nodes(), {good_section()});
    NodeSupport clamp, driven;
    driven.node = 2;
    driven.target_rotation = 1.01 * Eigen::Matrix3d::Identity();  // not orthonormal
    expect_model_error(
        [&] {
            validate_supports(beam, {clamp, driven});
        },
        {"supports[1].target_rotation"});
    driven.target_rotation =
        Eigen::Vector3d(1, 1, -1).asDiagonal();  // orthonormal but a reflection
    expect_model_error(
        [&] {
            solve_static(beam, BeamLoads{}, {clamp, driven});
        },
        {"supports[1].target_rotation"});
    driven.target_rotation.reset();
    driven.target_position_mm = Vec3(std::nan(""), 0, 0);
    expect_model_error(
        [&] {
            solve_static(beam, BeamLoads{}, {clamp, driven});
        },
        {"supports[1].target_position_mm"});
}

TEST(BadInput, BadSolverSettingsAreNamed) {
    ScopeBeam beam(three_nodes(), {good_section()});
    NodeSupport clamp;
    StaticSettings no_steps;
    no_steps.load_steps = 0;
    expect_model_error([&] { solve_static(beam, BeamLoads{}, {clamp}, no_steps); }, {"load_steps"});
    StaticSettings bad_tolerance;
    bad_tolerance.relative_tolerance = -1.0;
    expect_model_error([&] { solve_static(beam, BeamLoads{}, {clamp}, bad_tolerance); },
                       {"relative_tolerance"});
}

TEST(BadInput, PlanarModesNeedABeamAlongX) {
    const ScopeBeam oblique = straight_beam(Vec3::Zero(), Vec3(1, 1, 0), 100.0, 5, good_section());
    expect_model_error([&] { planar_bending_modes(oblique, RayleighDamping{}, 1); }, {"node 1"});
}

TEST(BadInput, StraightBeamArgumentsAreNamed) {
    expect_model_error([] { straight_beam(Vec3::Zero(), Vec3::UnitX(), 0.0, 5, good_section()); },
                       {"length_mm"});
    expect_model_error([] { straight_beam(Vec3::Zero(), Vec3::UnitX(), 100.0, 0, good_section()); },
                       {"element_count"});
    expect_model_error([] { straight_beam(Vec3::Zero(), Vec3::Zero(), 100.0, 5, good_section()); },
                       {"direction"});
}

}  // namespace
}  // namespace scopekin::model
