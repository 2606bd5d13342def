#include "model/colon/bundled_colons.hpp"

#include <cmath>
#include <string>

#include "model/model_error.hpp"

namespace scopekin::model {

ColonTube default_colon(double scope_radius_mm) {
    using R = ColonRegion;
    // Waypoints (x, y, z) mm, inner radius mm, region of the stretch starting there.
    const std::vector<ColonPoint> waypoints{
        {{0, 0, 0}, 18.0, R::rectum},
        {{0, 60, -25}, 18.0, R::rectum},
        {{5, 120, -35}, 17.0, R::rectum},
        {{10, 150, -25}, 15.0, R::sigmoid},  // recto-sigmoid junction
        {{-30, 185, 10}, 14.0, R::sigmoid},
        {{-60, 222, 40}, 14.0, R::sigmoid},
        {{-60, 272, 65}, 14.0, R::sigmoid},
        {{-10, 298, 75}, 14.0, R::sigmoid},
        {{45, 288, 55}, 14.0, R::sigmoid},
        {{90, 270, 25}, 13.0, R::sigmoid},
        {{115, 255, -10},
         12.5,
         R::descending},  // sigmoid-descending junction: the narrowest, 25 mm
        {{125, 340, -25}, 15.0, R::descending},
        {{130, 430, -30}, 15.0, R::descending},
        {{128, 500, -25}, 17.0, R::splenic_flexure},
        {{110, 545, -5}, 19.0, R::splenic_flexure},
        {{75, 555, 20}, 22.0, R::transverse},
        {{25, 470, 60}, 22.0, R::transverse},
        {{-40, 385, 75}, 22.0, R::transverse},
        {{-110, 430, 60}, 22.0, R::transverse},
        {{-160, 525, 25}, 22.0, R::hepatic_flexure},
        {{-185, 510, 0}, 23.0, R::hepatic_flexure},
        {{-190, 475, -15}, 23.0, R::ascending},
        {{-190, 400, -20}, 23.0, R::ascending},
        {{-185, 330, -20}, 24.0, R::cecum},
        {{-180, 285, -15}, 24.0, R::cecum},
    };
    return ColonTube("default", sample_centerline(waypoints, 10.0), scope_radius_mm);
}

ColonTube straight_tube(double length_mm, double inner_radius_mm, ColonRegion region,
                        double scope_radius_mm) {
    require_positive(length_mm, "straight_tube length_mm");
    const std::size_t pieces = centerline_pieces(length_mm, 10.0, "straight_tube length_mm");
    std::vector<ColonPoint> points;
    for (std::size_t i = 0; i <= pieces; ++i)
        points.push_back({{length_mm * static_cast<double>(i) / static_cast<double>(pieces), 0, 0},
                          inner_radius_mm,
                          region});
    return ColonTube("straight_tube", std::move(points), scope_radius_mm);
}

ColonTube single_bend(double lead_mm, double bend_radius_mm, double bend_angle_rad,
                      double inner_radius_mm, ColonRegion region, double scope_radius_mm) {
    require_positive(lead_mm, "single_bend lead_mm");
    require_positive(bend_radius_mm, "single_bend bend_radius_mm");
    require_positive(bend_angle_rad, "single_bend bend_angle_rad");
    if (bend_angle_rad > M_PI) throw ModelError("single_bend bend_angle_rad: must be <= pi");
    std::vector<ColonPoint> points;
    const std::size_t lead_pieces = centerline_pieces(lead_mm, 10.0, "single_bend lead_mm");
    for (std::size_t i = 0; i < lead_pieces; ++i)
        points.push_back(
            {{lead_mm * static_cast<double>(i) / static_cast<double>(lead_pieces), 0, 0},
             inner_radius_mm,
             region});
    const std::size_t bend_pieces =
        centerline_pieces(bend_radius_mm * bend_angle_rad, 10.0, "single_bend bend_radius_mm");
    const Eigen::Vector3d centre(lead_mm, bend_radius_mm, 0.0);
    for (std::size_t i = 0; i < bend_pieces; ++i) {
        const double a = bend_angle_rad * static_cast<double>(i) / static_cast<double>(bend_pieces);
        points.push_back({centre + bend_radius_mm * Eigen::Vector3d(std::sin(a), -std::cos(a), 0.0),
                          inner_radius_mm, region});
    }
    const Eigen::Vector3d exit_start =
        centre +
        bend_radius_mm * Eigen::Vector3d(std::sin(bend_angle_rad), -std::cos(bend_angle_rad), 0.0);
    const Eigen::Vector3d exit_direction(std::cos(bend_angle_rad), std::sin(bend_angle_rad), 0.0);
    for (std::size_t i = 0; i <= lead_pieces; ++i)
        points.push_back({exit_start + exit_direction * (lead_mm * static_cast<double>(i) /
                                                         static_cast<double>(lead_pieces)),
                          inner_radius_mm, region});
    return ColonTube("single_bend", std::move(points), scope_radius_mm);
}

}  // namespace scopekin::model
