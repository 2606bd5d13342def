#pragma once
// Contact detection between the scope and the colon wall (thesis 4.4): the scope is a chain of
// nodes of radius r_s inside a tube whose lumen has radius r(s) around the colon's current
// centerline. For each scope node: the closest point on the centerline, the gap to the wall
// g = r(s) - r_s - distance (mm, negative = penetration), and the contact frame
//   n: from the scope node towards the centerline (the direction the wall pushes the scope),
//   t: along the colon (towards the cecum) made orthogonal to n,   s = n x t.
// Nodes whose closest point lies before the anus (outside the body) get no contact. Several
// contacts at once: every node with g below the activation distance is a candidate.
#include <Eigen/Dense>
#include <vector>

#include "model/beam/scope_beam.hpp"
#include "model/colon/colon_tube.hpp"

namespace scopekin::model {

struct ContactCandidate {
    std::size_t scope_node = 0;
    std::size_t colon_segment = 0;  ///< centerline segment j (points j, j+1)
    double colon_weight = 0;        ///< position on the segment in [0, 1] (0 at point j)
    Eigen::Vector3d centerline_point_mm = Eigen::Vector3d::Zero();
    double gap_mm = 0;
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  ///< columns n, t, s
    ColonRegion region = ColonRegion::rectum;
};

struct ContactDetectionSettings {
    double scope_radius_mm = 6.65;
    /// Nodes closer to the wall than this become candidates (the solver decides if they touch).
    double activation_distance_mm = 2.0;
};

/// `colon` holds the colon's current node positions (one node per point of `tube`).
std::vector<ContactCandidate> detect_contacts(const ScopeBeam& scope, const ScopeBeam& colon,
                                              const ColonTube& tube,
                                              const ContactDetectionSettings& settings);

/// Where each scope node was on the centerline last time (-1: not yet tracked), so that time
/// stepping searches only nearby segments: O(nodes) instead of O(nodes x segments), and a node
/// cannot jump to a part of the colon that is close in space but far along the colon (the
/// loops of the sigmoid). A tracked node is only ever searched within its window: the search is
/// against the colon at rest, and a node of a mobile stretch that the scope has pushed away
/// (with its colon) lies far from it; until 2026-11-27 such a node, more than a lumen diameter
/// from its window, was searched for along the whole colon and put on whatever part lay nearer
/// at rest (in the CI's p0005-push-30 the tip, 35.7 mm from its own segment in the bowed
/// sigmoid, went to one 35.1 mm away in the transverse colon).
struct CenterlineTracking {
    std::vector<long> segment;
    std::size_t window_segments = 3;
};

/// The same detection against colon centerline positions (one per tube point), skipping the
/// scope nodes flagged in `skip_node` (may be empty), with tracking.
std::vector<ContactCandidate> detect_contacts(const ScopeBeam& scope,
                                              const std::vector<Eigen::Vector3d>& colon_mm,
                                              const ColonTube& tube,
                                              const ContactDetectionSettings& settings,
                                              const std::vector<bool>& skip_node,
                                              CenterlineTracking* tracking);

}  // namespace scopekin::model
