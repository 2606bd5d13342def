// Contact detection between scope and colon: gaps and frames against hand geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_beam.hpp"
#include "model/contact/contact_detection.hpp"
#include "model/scope/cf_q160l.hpp"

namespace scopekin::model {
namespace {

constexpr double kScopeRadius_mm = 6.65;

ScopeBeam colon_nodes(const ColonTube& tube) {
    return build_colon_structure(tube, default_colon_properties()).beam;
}

TEST(ContactDetection, CentredScopeInAStraightTubeTouchesNothing) {
    const ColonTube tube = straight_tube(300.0, 15.0, ColonRegion::descending, kScopeRadius_mm);
    const ScopeBeam scope =
        straight_beam({5, 0, 0}, Eigen::Vector3d::UnitX(), 250.0, 25, cf_q160l::section());
    ContactDetectionSettings settings;
    settings.activation_distance_mm = 100.0;  // report every node to check the gaps
    const auto contacts = detect_contacts(scope, colon_nodes(tube), tube, settings);
    ASSERT_EQ(contacts.size(), scope.node_count());
    for (const auto& c : contacts)
        EXPECT_NEAR(c.gap_mm, 15.0 - kScopeRadius_mm, 1e-9);  // lumen - scope
    settings.activation_distance_mm = 2.0;
    EXPECT_TRUE(detect_contacts(scope, colon_nodes(tube), tube, settings).empty());
}

TEST(ContactDetection, OffsetScopeGetsGapAndFrame) {
    // Scope shifted 5 mm towards +z: gap 15 - 6.65 - 5 = 3.35 mm, n = -z (towards the centerline),
    // t = +x (along the colon), s = n x t = -y.
    const ColonTube tube = straight_tube(300.0, 15.0, ColonRegion::descending, kScopeRadius_mm);
    const ScopeBeam scope =
        straight_beam({5, 0, 5}, Eigen::Vector3d::UnitX(), 250.0, 25, cf_q160l::section());
    ContactDetectionSettings settings;
    settings.activation_distance_mm = 5.0;
    const auto contacts = detect_contacts(scope, colon_nodes(tube), tube, settings);
    ASSERT_EQ(contacts.size(), scope.node_count());
    for (const auto& c : contacts) {
        EXPECT_NEAR(c.gap_mm, 3.35, 1e-9);
        EXPECT_TRUE(c.frame.col(0).isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
        EXPECT_TRUE(c.frame.col(1).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
        EXPECT_TRUE(c.frame.col(2).isApprox(Eigen::Vector3d(0, -1, 0), 1e-12));
        EXPECT_EQ(c.region, ColonRegion::descending);
    }
}

TEST(ContactDetection, StraightScopeMeetsTheOuterWallOfABend) {
    // Bend of centerline radius R = 40 mm centred at (100, 40): a straight scope continuing along
    // +x from the bend's start is at distance sqrt(30^2 + R^2) - R = 10 mm from the arc at x = 130,
    // i.e. gap = 15 - 6.65 - 10 = -1.65 mm (pressing into the outer wall), and the wall pushes it
    // towards the centre of the bend. Tolerance: the centerline is a polygon of 10 mm chords,
    // whose sagitta on R = 40 mm is 10^2 / (8 R) = 0.31 mm.
    const ColonTube bend =
        single_bend(100.0, 40.0, M_PI / 2.0, 15.0, ColonRegion::sigmoid, kScopeRadius_mm);
    const ScopeBeam scope =
        straight_beam({10, 0, 0}, Eigen::Vector3d::UnitX(), 120.0, 12, cf_q160l::section());
    ContactDetectionSettings settings;
    const auto contacts = detect_contacts(scope, colon_nodes(bend), bend, settings);
    const ContactCandidate* at130 = nullptr;
    for (const auto& c : contacts)
        if (c.scope_node == 12) at130 = &c;
    ASSERT_NE(at130, nullptr);
    EXPECT_NEAR(at130->gap_mm, 15.0 - kScopeRadius_mm - 10.0, 0.35);
    const Eigen::Vector3d to_centre =
        (Eigen::Vector3d(100, 40, 0) - Eigen::Vector3d(130, 0, 0)).normalized();
    EXPECT_GT(at130->frame.col(0).dot(to_centre), 0.99);
    // Nodes on the straight lead, away from the bend, are centred: no contact.
    for (const auto& c : contacts)
        EXPECT_GE(scope.position(c.scope_node).x(), 100.0);
}

TEST(ContactDetection, NodesOutsideTheBodyAreIgnored) {
    const ColonTube tube = straight_tube(300.0, 15.0, ColonRegion::rectum, kScopeRadius_mm);
    // The handle end lies 100 mm before the anus, offset so it would "penetrate" if it counted.
    const ScopeBeam scope =
        straight_beam({-100, 0, 12}, Eigen::Vector3d::UnitX(), 50.0, 5, cf_q160l::section());
    EXPECT_TRUE(detect_contacts(scope, colon_nodes(tube), tube, {}).empty());
}

// A hairpin: two straight limbs 80 mm apart joined by a 180° bend. A node tracked on the first
// limb stays on the first limb however far it is from it at rest (the search is against the
// colon at rest; a mobile stretch pushed away by the scope carries the node with it), even
// where the second limb lies nearer: only its window is searched.
TEST(ContactDetection, ATrackedNodeStaysOnItsOwnPartOfTheColonWhereverItIs) {
    const ColonTube hairpin =
        single_bend(200.0, 40.0, M_PI, 15.0, ColonRegion::sigmoid, kScopeRadius_mm);
    std::vector<Eigen::Vector3d> colon;
    for (const ColonPoint& p : hairpin.points())
        colon.push_back(p.position_mm);
    const std::size_t first_limb_segment = 10;  // around x = 100 mm on the first limb
    const Eigen::Vector3d on_first = hairpin.points()[first_limb_segment].position_mm;
    ContactDetectionSettings settings;
    settings.activation_distance_mm = 1000.0;  // report every node

    CenterlineTracking tracking;
    tracking.segment.assign(2, static_cast<long>(first_limb_segment));
    const Eigen::Vector3d across(0, 75.0, 0);  // 5 mm from the second limb (y = 80 mm)
    const ScopeBeam far =
        straight_beam(on_first + across, Eigen::Vector3d::UnitX(), 5.0, 1, cf_q160l::section());
    const auto tracked = detect_contacts(far, colon, hairpin, settings, {}, &tracking);
    ASSERT_EQ(tracked.size(), 2U);
    for (const ContactCandidate& c : tracked) {
        EXPECT_LE(c.colon_segment, first_limb_segment + 3) << "node " << c.scope_node;
        EXPECT_NEAR(c.gap_mm, 15.0 - kScopeRadius_mm - 75.0, 1.0);  // 75 mm from its own limb
    }
    // Untracked, the same node is placed on the limb it is nearest to.
    CenterlineTracking fresh;
    const auto found = detect_contacts(far, colon, hairpin, settings, {}, &fresh);
    ASSERT_EQ(found.size(), 2U);
    EXPECT_GT(found[0].colon_segment, first_limb_segment + 10);
    EXPECT_NEAR(found[0].gap_mm, 15.0 - kScopeRadius_mm - 5.0, 1.0);
}

}  // namespace
}  // namespace scopekin::model
