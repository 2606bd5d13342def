// The straightened path (model/colon/straightened_path.hpp): the scope's path to the cecum with the
// mobile regions drawn straight between their fixed ends. Expected values are closed forms of the
// made-up centerlines (Pythagoras, chords) and bounds any path obeys.
#include <gtest/gtest.h>

#include <cmath>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_beam.hpp"
#include "model/colon/straightened_path.hpp"
#include "model/patient/patient.hpp"
#include "model/scope/cf_q160l.hpp"

namespace {
using namespace scopekin::model;
using R = ColonRegion;

std::array<ColonRegionProperties, 8> all_fixed() {
    std::array<ColonRegionProperties, 8> p = default_colon_properties();
    for (auto& r : p) {
        r.attachment = ColonAttachment::fixed;
        r.mesentery_stiffness_N_per_mm2 = 0;
    }
    return p;
}

TEST(StraightenedPath, FixedZigZagKeepsEverySegment) {
    const std::vector<ColonPoint> points{{{0, 0, 0}, 15.0, R::rectum},
                                         {{10, 5, 0}, 15.0, R::rectum},
                                         {{20, 0, 0}, 15.0, R::descending}};
    EXPECT_NEAR(straightened_path_mm(points, all_fixed()), 2.0 * std::sqrt(125.0), 1e-12);
}

TEST(StraightenedPath, MobileLoopBecomesItsChord) {
    // Rectum 100 mm up, a sigmoid bowing 80 mm out (a half ellipse between points 60 mm apart),
    // then 200 mm of descending colon: 100 + 60 + 200 mm whatever the sigmoid's shape.
    std::vector<ColonPoint> points{{{0, 0, 0}, 15.0, R::rectum}};
    for (int i = 0; i <= 12; ++i) {
        const double a = M_PI * static_cast<double>(i) / 12.0;
        points.push_back({{30.0 - 30.0 * std::cos(a), 100.0 + 80.0 * std::sin(a), 0},
                          15.0,
                          i == 12 ? R::descending : R::sigmoid});
    }
    points.push_back({{60, 300, 0}, 15.0, R::descending});
    const auto properties = default_colon_properties();  // sigmoid on a mesentery
    ASSERT_EQ(properties[static_cast<std::size_t>(R::sigmoid)].attachment,
              ColonAttachment::mesentery);
    EXPECT_NEAR(straightened_path_mm(points, properties), 360.0, 1e-9);
}

TEST(StraightenedPath, DefaultColonBetweenTheStraightLineAndItsLength) {
    const ColonTube colon = default_colon(cf_q160l::kRadius_mm);
    const double fixed = straightened_path_mm(colon.points(), all_fixed());
    const double straightened = straightened_path_mm(colon.points(), default_colon_properties());
    const double anus_to_cecum =
        (colon.points().back().position_mm - colon.points().front().position_mm).norm();
    EXPECT_NEAR(fixed, colon.length_mm(), 1e-9 * colon.length_mm());  // nothing straightened
    EXPECT_LT(straightened, colon.length_mm());
    EXPECT_GT(straightened, anus_to_cecum);
}

TEST(StraightenedPath, MobileDescendingColonShortensIt) {
    // The same patient with its descending colon on a mesentery: the sigmoid, descending colon and
    // the splenic flexure's neighbours form one longer run, whose chord is no longer than the path.
    PatientSpec p = draw_patient(7);
    p.descending_mobile = false;
    const double fixed = measure_patient(p).straightened_path_mm;
    p.descending_mobile = true;
    const double mobile = measure_patient(p).straightened_path_mm;
    EXPECT_LT(mobile, fixed);
    EXPECT_LT(fixed, p.total_length_mm());
}

}  // namespace
