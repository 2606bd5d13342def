#pragma once
// What the box claims to estimate, read off the full-order world after a step through its
// public API only (model/truth/README.md): the tip's place along the displaced colon
// centerline, each estimator station's resultant wall force in its (n, t, s) frame, the largest
// station force and the largest single wall force with its place, and what a loop's type and
// region are judged from (the colon region displaced farthest from rest, whether the inserted
// scope crosses itself in the frontal view). Cost per read: O(colon points + scope nodes +
// contacts), plus O(inserted nodes^2) bounding-box tests for the crossing.
#include <Eigen/Dense>
#include <cstddef>
#include <vector>

#include "model/colon/colon_region.hpp"
#include "model/truth/truth_definitions.hpp"
#include "model/world/world.hpp"

namespace scopekin::model::truth {

/// The estimator's stations (firmware/kinetics: kStationCapacity stations 50 mm apart): their
/// count, spacing and scope nodes, station 0 (the tip) first.
struct StationLayout {
    std::size_t stations = 12;
    double spacing_mm = 50.0;
    /// Tip first; fewer than `stations` when the scope is shorter than the stations' span (the
    /// stations past its end are never inside and carry no force).
    std::vector<std::size_t> nodes;
};
/// The layout of `stations` stations `spacing_mm` apart on this world's scope, exactly as the
/// reduction places them (model::station_nodes: throws ModelError when a station falls between
/// nodes or off the scope). The accuracy tests use this one.
StationLayout station_layout(const World& world, std::size_t stations = 12,
                             double spacing_mm = 50.0);
/// The same on any scope (truth.csv of any scenario): station j at the node nearest to
/// j x spacing from the tip, and only the stations that fit on the scope.
StationLayout nearest_station_layout(const World& world, std::size_t stations = 12,
                                     double spacing_mm = 50.0);

/// Where a point is along a colon centerline given by its current points and their arc lengths
/// at rest: the closest point of the segments whose rest arc overlaps [from_mm, to_mm].
struct CenterlinePlace {
    bool found = false;
    std::size_t segment = 0;
    double weight = 0;             ///< along the segment, [0, 1]
    double path_mm = 0;            ///< colon coordinate: the rest arc length there
    double displaced_path_mm = 0;  ///< arc length along the current (displaced) polyline
    double distance_mm = 0;        ///< from the point to the centerline
};
/// `displaced_arc_mm`: the current polyline's cumulative lengths (displaced_arc_lengths).
/// Throws ModelError when the vectors' lengths differ or fewer than 2 points are given.
CenterlinePlace locate_on_centerline(const std::vector<Eigen::Vector3d>& points_mm,
                                     const std::vector<double>& rest_arc_mm,
                                     const std::vector<double>& displaced_arc_mm,
                                     const Eigen::Vector3d& point_mm, double from_mm, double to_mm);
/// Cumulative arc length along a polyline [mm], 0 at the first point.
std::vector<double> displaced_arc_lengths(const std::vector<Eigen::Vector3d>& points_mm);

/// Whether a polyline crosses itself in the x-y plane (the frontal view: x the patient's left,
/// y cranial); segments that share a point do not count.
bool crosses_itself_xy(const std::vector<Eigen::Vector3d>& points_mm);

struct StationTruth {
    bool inside = false;  ///< past the anus
    double path_mm = 0;   ///< colon coordinate of the closest displaced centerline point
    double displaced_path_mm = 0;
    ColonRegion region = ColonRegion::rectum;
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  ///< columns n, t, s (body frame)
    Eigen::Vector3d force_N = Eigen::Vector3d::Zero();    ///< resultant wall force (n, t, s)
};

struct TruthReadout {
    double time_s = 0;
    double insertion_mm = 0;
    double tip_path_mm = 0;            ///< colon coordinate (= station 0's path_mm)
    double tip_displaced_path_mm = 0;  ///< arc along the displaced centerline
    ColonRegion tip_region = ColonRegion::rectum;
    std::vector<StationTruth> stations;  ///< tip first
    double max_station_force_N = 0;      ///< largest |f| over stations (the firmware's quantity)
    std::size_t max_station = 0;
    double max_wall_force_N = 0;  ///< largest |wall force| of one contact (normal + friction)
    double max_wall_path_mm = 0;  ///< its colon coordinate
    ColonRegion max_wall_region = ColonRegion::rectum;
    bool has_wall_force = false;
    ColonRegion bow_region = ColonRegion::rectum;  ///< region of the colon point moved farthest
    double bow_mm = 0;                             ///< how far it moved from rest
    RegionBow region_bow_mm{};   ///< per region (kColonRegionsInOrder), its farthest move
    bool scope_crosses = false;  ///< the inserted scope crosses itself in the frontal view
    /// How far the scope's axis lies beyond the colon wall [mm], the largest over the stations
    /// inside: distance to the displaced centerline minus the lumen's radius there (a scope
    /// resting on the wall: minus its own radius, 6.65 mm for the CF-Q160L). Beyond
    /// kThroughWall_mm the scope has gone through the wall and the run is not physical.
    double scope_beyond_wall_mm = 0;
};

/// Reads TruthReadouts off one world.
class TruthReader {
public:
    /// `gravity_mm_per_s2`: the world's gravity in the body frame (the scenario's); it settles the
    /// station frame of a node that sits exactly on the centerline, as World::probe_stations does.
    TruthReader(const World& world, StationLayout layout, const Eigen::Vector3d& gravity_mm_per_s2);
    TruthReadout read(const World& world) const;
    const StationLayout& layout() const { return layout_; }

    /// A station the contact detection does not track yet (before the first step) is searched
    /// from this far back along the colon from where its arc allows up to 5 mm past it
    /// (World::centerline_search_window_mm; a tracked one is searched around its tracked segment).
    static constexpr double kSearchBack_mm = 400.0;
    /// The scope's axis this far beyond the wall: through it. The distance is measured to the
    /// displaced centerline, which the contact model only linearises: on development_scripted
    /// (2026-11-27) runs whose station forces stayed <= 31 N read up to 28.5 mm, the one run
    /// whose station force reached 225 N read 47.5 mm. 40 mm is six scope radii.
    static constexpr double kThroughWall_mm = 40.0;

private:
    StationLayout layout_;
    Eigen::Vector3d gravity_;
    Eigen::Vector3d anus_;
    Eigen::Vector3d entry_;
    std::vector<double> rest_arc_mm_;
};

}  // namespace scopekin::model::truth
