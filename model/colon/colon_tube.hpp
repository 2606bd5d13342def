#pragma once
// The colon's centerline: points every few mm from the anus to the cecum, each with the region
// it belongs to and the lumen's inner radius there (thesis 4.3.2, Fig. 4.16). Validated on
// construction: regions in anatomical order, radii positive and larger than the scope, and no
// self-intersection (the lumens of two parts of the colon that are far apart along it may touch
// but never overlap).
#include <Eigen/Dense>
#include <cstddef>
#include <string>
#include <vector>

#include "model/colon/colon_region.hpp"

namespace scopekin::model {

struct ColonPoint {
    Eigen::Vector3d position_mm;
    double inner_radius_mm = 0;
    ColonRegion region =
        ColonRegion::rectum;  ///< region of the segment from this point to the next
};

class ColonTube {
public:
    /// Throws ModelError naming the point or region for an impossible colon.
    /// `scope_radius_mm`: the lumen must be wider than the scope everywhere.
    ColonTube(std::string name, std::vector<ColonPoint> points, double scope_radius_mm);

    const std::string& name() const { return name_; }
    const std::vector<ColonPoint>& points() const { return points_; }
    std::size_t point_count() const { return points_.size(); }
    /// Arc length from the anus to point i [mm].
    double arc_length_mm(std::size_t i) const { return arc_length_[i]; }
    double length_mm() const { return arc_length_.back(); }
    /// Length of each region along the centerline [mm] (0 for absent regions), in kColonRegionsInOrder order.
    std::array<double, 8> region_lengths_mm() const;
    /// The centerline point closest to `point` among the segments within `window_mm` of arc length
    /// `near_path_mm` (a tracked point moves little between calls, and the window keeps it off other
    /// turns of a loop that happen to be near in space). Returns false if no segment is in the
    /// window or the point is not finite; else its arc length from the anus and the segment index.
    bool closest_point_near(const Eigen::Vector3d& point, double near_path_mm, double window_mm,
                            double& path_mm, std::size_t& segment) const;
    /// Narrowest inner radius and the arc length where it occurs.
    std::pair<double, double> narrowest_radius_mm() const;

private:
    std::string name_;
    std::vector<ColonPoint> points_;
    std::vector<double> arc_length_;
};

/// At most this many centerline points in one colon (1 km at 10 mm): a length that would need more
/// is an input error, refused before anything is allocated.
inline constexpr std::size_t kMaxCenterlinePoints = 100000;

/// The number of pieces of at most `spacing_mm` that cover `length_mm` (at least 1), refused with
/// `field` named (ModelError) when it would pass kMaxCenterlinePoints or is not finite.
std::size_t centerline_pieces(double length_mm, double spacing_mm, const std::string& field);

/// A smooth centerline through waypoints (centripetal-free uniform Catmull-Rom spline), sampled
/// so that consecutive points are at most `spacing_mm` apart. Each waypoint carries the region
/// of the stretch that starts there and the inner radius there (linearly interpolated between).
std::vector<ColonPoint> sample_centerline(const std::vector<ColonPoint>& waypoints,
                                          double spacing_mm);

}  // namespace scopekin::model
