// Colon geometry: the bundled colons have the documented dimensions, and impossible colons are
// rejected with a message naming the point or region.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "model/colon/bundled_colons.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

constexpr double kScopeRadius_mm = 6.65;

void expect_error(const std::function<void()>& build, const std::string& fragment) {
    try {
        build();
        ADD_FAILURE() << "no error; expected one mentioning '" << fragment << "'";
    } catch (const ModelError& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
}

TEST(DefaultColon, HasHumanDimensions) {
    const ColonTube colon = default_colon(kScopeRadius_mm);
    // CT colonography: 150.3 +- 18.5 cm (Utano et al. 2022): within one standard deviation.
    EXPECT_NEAR(colon.length_mm(), 1503.0, 185.0);
    const auto lengths = colon.region_lengths_mm();
    for (double l : lengths)
        EXPECT_GT(l, 0.0);  // every region present
    // Transverse the longest segment, then the sigmoid (cadaver study 2015).
    const double transverse = lengths[static_cast<std::size_t>(ColonRegion::transverse)];
    const double sigmoid = lengths[static_cast<std::size_t>(ColonRegion::sigmoid)];
    for (double l : lengths)
        EXPECT_LE(l, transverse);
    for (std::size_t i = 0; i < lengths.size(); ++i)
        if (i != static_cast<std::size_t>(ColonRegion::transverse)) {
            EXPECT_LE(lengths[i], sigmoid);
        }
    // Narrowest lumen 25 mm (model/PHYSICS.md §3.3) at the sigmoid-descending junction.
    const auto [radius, where] = colon.narrowest_radius_mm();
    EXPECT_DOUBLE_EQ(radius, 12.5);
    const double junction = lengths[0] + lengths[1];
    EXPECT_NEAR(where, junction, 1.0);
}

TEST(DefaultColon, RegionsRunInAnatomicalOrder) {
    const ColonTube colon = default_colon(kScopeRadius_mm);
    EXPECT_EQ(colon.points().front().region, ColonRegion::rectum);
    EXPECT_EQ(colon.points().back().region, ColonRegion::cecum);
    for (std::size_t i = 1; i < colon.point_count(); ++i)
        EXPECT_LE(static_cast<int>(colon.points()[i - 1].region),
                  static_cast<int>(colon.points()[i].region));
}

TEST(DefaultColon, CenterlinePointsAtMost10mmApart) {
    const ColonTube colon = default_colon(kScopeRadius_mm);
    for (std::size_t i = 1; i < colon.point_count(); ++i)
        EXPECT_LE(colon.arc_length_mm(i) - colon.arc_length_mm(i - 1), 10.0 + 1e-9);
}

TEST(SingleBend, LengthIsTwoLeadsPlusTheArc) {
    // Centerline = 2 straight leads + R * angle exactly, up to the chord error of a 10 mm polygon
    // on the arc (R (angle - 2 n sin(angle / 2n)) < 0.1 mm here).
    const ColonTube bend =
        single_bend(100.0, 40.0, M_PI / 2.0, 15.0, ColonRegion::sigmoid, kScopeRadius_mm);
    EXPECT_NEAR(bend.length_mm(), 200.0 + 40.0 * M_PI / 2.0, 0.2);
    EXPECT_NEAR(bend.points().back().position_mm.x(), 140.0, 1e-9);
    EXPECT_NEAR(bend.points().back().position_mm.y(), 140.0, 1e-9);
}

TEST(StraightTube, IsStraight) {
    const ColonTube tube = straight_tube(300.0, 15.0, ColonRegion::descending, kScopeRadius_mm);
    EXPECT_DOUBLE_EQ(tube.length_mm(), 300.0);
    for (const auto& p : tube.points())
        EXPECT_EQ(p.position_mm.y(), 0.0);
}

TEST(ImpossibleColon, LumenNarrowerThanTheScope) {
    expect_error(
        [] { straight_tube(100.0, 6.0, ColonRegion::sigmoid, kScopeRadius_mm); },
        "point 0 (sigmoid): inner radius 6.000000 mm is not larger than the scope's radius");
}

TEST(ImpossibleColon, SelfIntersectingCenterline) {
    // A loop that comes back through its own start: a square spiral closing on itself.
    std::vector<ColonPoint> points;
    const std::vector<Eigen::Vector3d> corners{
        {0, 0, 0}, {200, 0, 0}, {200, 200, 0}, {100, 200, 0}, {100, -100, 0}};
    for (const auto& c : corners)
        points.push_back({c, 15.0, ColonRegion::sigmoid});
    expect_error([&] { ColonTube("spiral", sample_centerline(points, 10.0), kScopeRadius_mm); },
                 "the centerline intersects itself");
}

TEST(ImpossibleColon, RegionsOutOfOrder) {
    std::vector<ColonPoint> points{{{0, 0, 0}, 15.0, ColonRegion::descending},
                                   {{10, 0, 0}, 15.0, ColonRegion::sigmoid},
                                   {{20, 0, 0}, 15.0, ColonRegion::sigmoid}};
    expect_error([&] { ColonTube("c", points, kScopeRadius_mm); },
                 "point 1: region sigmoid comes after descending");
}

TEST(ImpossibleColon, CoincidentPointsAndNaN) {
    std::vector<ColonPoint> points{{{0, 0, 0}, 15.0, ColonRegion::sigmoid},
                                   {{0, 0, 0}, 15.0, ColonRegion::sigmoid}};
    expect_error([&] { ColonTube("c", points, kScopeRadius_mm); },
                 "point 1: coincides with point 0");
    points[1].position_mm.y() = std::nan("");
    expect_error([&] { ColonTube("c", points, kScopeRadius_mm); }, "point 1 coordinate y (mm)");
}

TEST(ColonRegions, NamesRoundTripAndThesisModuli) {
    for (ColonRegion r : kColonRegionsInOrder)
        EXPECT_EQ(region_from_name(region_name(r)), r);
    EXPECT_FALSE(region_from_name("appendix").has_value());
    // Thesis Table 4.6, longitudinal, kPa.
    EXPECT_EQ(default_region_properties(ColonRegion::rectum).young_modulus_kPa, 398.0);
    EXPECT_EQ(default_region_properties(ColonRegion::sigmoid).young_modulus_kPa, 360.0);
    EXPECT_EQ(default_region_properties(ColonRegion::descending).young_modulus_kPa, 318.0);
    EXPECT_EQ(default_region_properties(ColonRegion::transverse).young_modulus_kPa, 892.0);
    EXPECT_EQ(default_region_properties(ColonRegion::ascending).young_modulus_kPa, 781.0);
    EXPECT_EQ(default_region_properties(ColonRegion::sigmoid).attachment,
              ColonAttachment::mesentery);
    EXPECT_EQ(default_region_properties(ColonRegion::transverse).attachment,
              ColonAttachment::mesentery);
    EXPECT_EQ(default_region_properties(ColonRegion::descending).attachment,
              ColonAttachment::fixed);
}

}  // namespace
}  // namespace scopekin::model
