// The colon as a structure: hollow Timoshenko beams, clamped fixed regions, mesentery springs.
#include <gtest/gtest.h>

#include <cmath>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_beam.hpp"
#include "model/solvers/static_solver.hpp"

namespace scopekin::model {
namespace {

TEST(HollowColonSection, MatchesHandComputation) {
    // Sigmoid: r = 14 mm, t = 2 mm, E = 360 kPa = 0.36 N/mm^2.
    // I = pi/4 (16^4 - 14^4) = pi/4 * 27120 mm^4; A = pi (16^2 - 14^2) = 60 pi mm^2.
    const BeamSection s = hollow_colon_section(14.0, 2.0, 360.0);
    EXPECT_NEAR(s.bending_stiffness_z_Nmm2, 0.36 * M_PI / 4.0 * 27120.0, 1e-9);
    EXPECT_NEAR(s.axial_stiffness_N, 0.36 * 60.0 * M_PI, 1e-9);
    EXPECT_NEAR(s.torsional_stiffness_Nmm2, 0.36 / (2.0 * 1.49) * M_PI / 2.0 * 27120.0, 1e-9);
    EXPECT_EQ(s.mass_per_length_t_per_mm, 0.0);  // Eq. 4.16: stiffness only
}

TEST(ColonStructure, FixedRegionsClampedMobileRegionsOnSprings) {
    const ColonTube tube = default_colon(6.65);
    const auto props = default_colon_properties();
    const ColonStructure c = build_colon_structure(tube, props);
    ASSERT_EQ(c.mobile.size(), tube.point_count());
    double spring_sum = 0.0, mobile_length = 0.0;
    for (const auto& s : c.loads.springs)
        spring_sum += s.stiffness_N_per_mm;
    for (std::size_t i = 0; i < tube.point_count(); ++i) {
        const ColonRegion r = tube.points()[i].region;
        const bool mesentery_region = r == ColonRegion::sigmoid || r == ColonRegion::transverse;
        if (c.mobile[i]) {
            EXPECT_TRUE(mesentery_region) << "node " << i;
            mobile_length += 0.5 * (tube.arc_length_mm(i + 1) - tube.arc_length_mm(i - 1));
        }
        if (!mesentery_region) {
            EXPECT_FALSE(c.mobile[i]) << "node " << i;
        }
    }
    EXPECT_EQ(c.supports.size() + c.loads.springs.size(), tube.point_count());
    // Springs carry k' = 2e-3 N/mm per mm of mobile colon.
    EXPECT_NEAR(spring_sum, 2e-3 * mobile_length, 1e-9);
    EXPECT_GT(mobile_length, 600.0);  // sigmoid (40 cm) + transverse (42 cm), less the border nodes
}

TEST(ColonStructure, MesenteryActsAsAnElasticFoundation) {
    // A long straight sigmoid on its mesentery, loaded at the middle, behaves as Hetenyi's infinite
    // beam on an elastic foundation: w(0) = P beta / (2 k'), beta = (k' / 4EI)^(1/4). Shear is made
    // rigid here because the closed form is Euler-Bernoulli; the tube is 10 decay lengths long.
    const ColonTube tube = straight_tube(600.0, 14.0, ColonRegion::sigmoid, 6.65);
    auto props = default_colon_properties();
    ColonStructure c = build_colon_structure(tube, props);
    std::vector<BeamSection> sections;
    for (std::size_t e = 0; e < c.beam.element_count(); ++e) {
        BeamSection s = c.beam.section(e);
        s.shear_stiffness_y_N = s.shear_stiffness_z_N = INFINITY;
        sections.push_back(s);
    }
    std::vector<Eigen::Vector3d> nodes;
    for (std::size_t i = 0; i < c.beam.node_count(); ++i)
        nodes.push_back(c.beam.reference_position(i));
    ScopeBeam beam(nodes, sections);
    const std::size_t middle = beam.node_count() / 2;
    const double load_N = 0.1;
    BeamLoads loads = c.loads;
    loads.nodal.push_back({middle, Eigen::Vector3d(0.0, load_N, 0.0), Eigen::Vector3d::Zero()});
    const StaticReport report = solve_static(beam, loads, c.supports);
    ASSERT_TRUE(report.converged) << report.message;
    const double k_foundation = 2e-3;  // N/mm per mm
    const double ei = beam.section(0).bending_stiffness_z_Nmm2;
    const double beta = std::pow(k_foundation / (4.0 * ei), 0.25);
    const double expected = load_N * beta / (2.0 * k_foundation);
    // 1 % : discrete springs every 10 mm (vs 1/beta = 63 mm) and clamped ends 4.8 decay lengths away.
    EXPECT_NEAR(beam.position(middle).y(), expected, 0.01 * expected);
}

}  // namespace
}  // namespace scopekin::model
