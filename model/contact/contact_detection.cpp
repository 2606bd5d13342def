#include "model/contact/contact_detection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

struct Closest {
    double distance = std::numeric_limits<double>::infinity();
    std::size_t segment = 0;
    double weight = 0, unclamped = 0;
};

Closest closest_segment(const Eigen::Vector3d& x, const std::vector<Eigen::Vector3d>& colon,
                        std::size_t first, std::size_t last) {
    Closest best;
    for (std::size_t j = first; j <= last; ++j) {
        const Eigen::Vector3d& a = colon[j];
        const Eigen::Vector3d ab = colon[j + 1] - a;
        const double unclamped = (x - a).dot(ab) / ab.squaredNorm();
        const double w = std::clamp(unclamped, 0.0, 1.0);
        const double d = (x - (a + w * ab)).norm();
        if (d < best.distance) best = {d, j, w, unclamped};
    }
    return best;
}

}  // namespace

std::vector<ContactCandidate> detect_contacts(const ScopeBeam& scope, const ScopeBeam& colon,
                                              const ColonTube& tube,
                                              const ContactDetectionSettings& settings) {
    std::vector<Eigen::Vector3d> positions(colon.node_count());
    for (std::size_t i = 0; i < colon.node_count(); ++i)
        positions[i] = colon.position(i);
    return detect_contacts(scope, positions, tube, settings, {}, nullptr);
}

std::vector<ContactCandidate> detect_contacts(const ScopeBeam& scope,
                                              const std::vector<Eigen::Vector3d>& colon,
                                              const ColonTube& tube,
                                              const ContactDetectionSettings& settings,
                                              const std::vector<bool>& skip_node,
                                              CenterlineTracking* tracking) {
    require_positive(settings.scope_radius_mm, "contact.scope_radius_mm");
    require_non_negative(settings.activation_distance_mm, "contact.activation_distance_mm");
    if (colon.size() != tube.point_count())
        throw ModelError(
            "contact detection: the colon structure and its tube have different point counts");
    if (tracking != nullptr) tracking->segment.resize(scope.node_count(), -1);
    std::vector<ContactCandidate> contacts;
    const std::size_t segments = colon.size() - 1;
    const auto& p = tube.points();
    for (std::size_t i = 0; i < scope.node_count(); ++i) {
        if (!skip_node.empty() && skip_node[i]) continue;
        const Eigen::Vector3d x = scope.position(i);
        Closest best;
        const long hint = tracking != nullptr ? tracking->segment[i] : -1;
        if (hint >= 0) {
            const auto h = static_cast<std::size_t>(hint);
            const std::size_t first =
                h > tracking->window_segments ? h - tracking->window_segments : 0;
            const std::size_t last = std::min(segments - 1, h + tracking->window_segments);
            // Only near where it was: the colon at rest is searched, and a node of a mobile stretch
            // pushed away with its colon (a loop bows the sigmoid 100 mm and more) is far from
            // it; a full search would put it on whatever other part of the colon lies nearer at
            // rest, and the contact would then act on the wrong colon.
            best = closest_segment(x, colon, first, last);
        } else {
            // O(nodes x segments) without tracking: ~3e4 point-segment tests for the full scope.
            best = closest_segment(x, colon, 0, segments - 1);
        }
        const bool outside_body = best.segment == 0 && best.unclamped < 0.0;  // before the anus
        if (tracking != nullptr)
            tracking->segment[i] = outside_body ? -1 : static_cast<long>(best.segment);
        if (outside_body) continue;
        const double lumen = (1.0 - best.weight) * p[best.segment].inner_radius_mm +
                             best.weight * p[best.segment + 1].inner_radius_mm;
        const double gap = lumen - settings.scope_radius_mm - best.distance;
        if (gap > settings.activation_distance_mm) continue;
        ContactCandidate c;
        c.scope_node = i;
        c.colon_segment = best.segment;
        c.colon_weight = best.weight;
        c.centerline_point_mm =
            colon[best.segment] + best.weight * (colon[best.segment + 1] - colon[best.segment]);
        c.gap_mm = gap;
        c.region = p[best.segment].region;
        const Eigen::Vector3d axis = (colon[best.segment + 1] - colon[best.segment]).normalized();
        Eigen::Vector3d n = c.centerline_point_mm - x;
        // A node (almost) on the centerline with a lumen narrower than the scope: push it sideways
        // along any direction normal to the axis (only possible in an invalid, too-narrow colon).
        if (n.norm() < 1e-9) n = axis.unitOrthogonal();
        n.normalize();
        Eigen::Vector3d t = axis - axis.dot(n) * n;
        // Past the last point n can lie along the axis: any tangent direction will do there.
        t = t.norm() > 1e-9 ? Eigen::Vector3d(t.normalized()) : n.unitOrthogonal();
        c.frame.col(0) = n;
        c.frame.col(1) = t;
        c.frame.col(2) = n.cross(t);
        contacts.push_back(c);
    }
    return contacts;
}

}  // namespace scopekin::model
