#include "model/contact/contact_detection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model_error.hpp"

namespace scopekin::model {

std::vector<ContactCandidate> detect_contacts(const ScopeBeam& scope, const ScopeBeam& colon, const ColonTube& tube,
                                              const ContactDetectionSettings& settings) {
  require_positive(settings.scope_radius_mm, "contact.scope_radius_mm");
  require_non_negative(settings.activation_distance_mm, "contact.activation_distance_mm");
  if (colon.node_count() != tube.point_count())
    throw ModelError("contact detection: the colon structure and its tube have different point counts");
  std::vector<ContactCandidate> contacts;
  const std::size_t segments = colon.node_count() - 1;
  for (std::size_t i = 0; i < scope.node_count(); ++i) {
    const Eigen::Vector3d x = scope.position(i);
    double best_distance = std::numeric_limits<double>::infinity();
    std::size_t best_segment = 0;
    double best_weight = 0.0, best_unclamped = 0.0;
    // O(nodes x segments): ~3e4 point-segment tests for the full scope in the full colon.
    for (std::size_t j = 0; j < segments; ++j) {
      const Eigen::Vector3d a = colon.position(j), b = colon.position(j + 1);
      const Eigen::Vector3d ab = b - a;
      const double unclamped = (x - a).dot(ab) / ab.squaredNorm();
      const double w = std::clamp(unclamped, 0.0, 1.0);
      const double d = (x - (a + w * ab)).norm();
      if (d < best_distance) {
        best_distance = d;
        best_segment = j;
        best_weight = w;
        best_unclamped = unclamped;
      }
    }
    if (best_segment == 0 && best_unclamped < 0.0) continue;  // before the anus: outside the body
    const auto& p = tube.points();
    const double lumen = (1.0 - best_weight) * p[best_segment].inner_radius_mm +
                         best_weight * p[best_segment + 1].inner_radius_mm;
    const double gap = lumen - settings.scope_radius_mm - best_distance;
    if (gap > settings.activation_distance_mm) continue;
    ContactCandidate c;
    c.scope_node = i;
    c.colon_segment = best_segment;
    c.colon_weight = best_weight;
    c.centerline_point_mm = colon.position(best_segment) +
                            best_weight * (colon.position(best_segment + 1) - colon.position(best_segment));
    c.gap_mm = gap;
    c.region = p[best_segment].region;
    const Eigen::Vector3d axis = (colon.position(best_segment + 1) - colon.position(best_segment)).normalized();
    Eigen::Vector3d n = c.centerline_point_mm - x;
    // A node (almost) on the centerline with a lumen narrower than the scope: push it sideways
    // along any direction normal to the axis (only possible in an invalid, too-narrow colon).
    if (n.norm() < 1e-9) n = axis.unitOrthogonal();
    n.normalize();
    const Eigen::Vector3d t = (axis - axis.dot(n) * n).normalized();
    c.frame.col(0) = n;
    c.frame.col(1) = t;
    c.frame.col(2) = n.cross(t);
    contacts.push_back(c);
  }
  return contacts;
}

}  // namespace scopekin::model
