#include "model/colon/colon_tube.hpp"

#include <limits>

#include <algorithm>
#include <cmath>
#include <string>

#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

std::size_t region_index(ColonRegion r) {
    return static_cast<std::size_t>(r);
}

/// Closest distance between segments [p0, p1] and [q0, q1] (Ericson, Real-Time Collision
/// Detection, 5.1.9).
double segment_distance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& q0, const Eigen::Vector3d& q1) {
    const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
    const double c = d1.dot(r), b = d1.dot(d2), denom = a * e - b * b;
    double s = denom > 1e-12 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
    double t = (b * s + f) / e;
    if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
    } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
    }
    return ((p0 + d1 * s) - (q0 + d2 * t)).norm();
}

Eigen::Vector3d catmull_rom(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                            const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, double t) {
    return 0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t +
                  (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t * t * t);
}

}  // namespace

ColonTube::ColonTube(std::string name, std::vector<ColonPoint> points, double scope_radius_mm)
    : name_(std::move(name)), points_(std::move(points)) {
    const std::string where = "colon '" + name_ + "'";
    if (points_.size() < 2) throw ModelError(where + ": needs at least 2 centerline points");
    require_positive(scope_radius_mm, where + ": scope radius (mm)");
    arc_length_.assign(points_.size(), 0.0);
    for (std::size_t i = 0; i < points_.size(); ++i) {
        const std::string at = where + " point " + std::to_string(i);
        for (int c = 0; c < 3; ++c)
            require_finite(points_[i].position_mm(c), at + " coordinate " + "xyz"[c] + " (mm)");
        require_positive(points_[i].inner_radius_mm, at + " inner_radius_mm");
        if (points_[i].inner_radius_mm <= scope_radius_mm)
            throw ModelError(at + " (" + std::string(region_name(points_[i].region)) +
                             "): inner radius " + std::to_string(points_[i].inner_radius_mm) +
                             " mm is not larger than the scope's radius " +
                             std::to_string(scope_radius_mm) + " mm");
        if (i > 0) {
            const double step = (points_[i].position_mm - points_[i - 1].position_mm).norm();
            if (!(step > 1e-6))
                throw ModelError(at + ": coincides with point " + std::to_string(i - 1));
            arc_length_[i] = arc_length_[i - 1] + step;
            if (region_index(points_[i].region) < region_index(points_[i - 1].region))
                throw ModelError(
                    at + ": region " + std::string(region_name(points_[i].region)) +
                    " comes after " + std::string(region_name(points_[i - 1].region)) +
                    " (regions must run rectum, sigmoid, descending, splenic_flexure, transverse, "
                    "hepatic_flexure, ascending, cecum)");
        }
    }
    // Self-intersection: two stretches far apart along the colon (more than half a turn of the
    // tube, pi (r_a + r_b)) must keep their lumens apart: centerline distance >= r_a + r_b.
    for (std::size_t i = 0; i + 1 < points_.size(); ++i) {
        for (std::size_t j = i + 2; j + 1 < points_.size(); ++j) {
            const double ri = std::max(points_[i].inner_radius_mm, points_[i + 1].inner_radius_mm);
            const double rj = std::max(points_[j].inner_radius_mm, points_[j + 1].inner_radius_mm);
            if (arc_length_[j] - arc_length_[i + 1] <= M_PI * (ri + rj)) continue;
            const double d = segment_distance(points_[i].position_mm, points_[i + 1].position_mm,
                                              points_[j].position_mm, points_[j + 1].position_mm);
            if (d < 0.999 * (points_[i].inner_radius_mm + points_[j].inner_radius_mm))
                throw ModelError(where + ": the centerline intersects itself: segment " +
                                 std::to_string(i) + " (" +
                                 std::string(region_name(points_[i].region)) + ", " +
                                 std::to_string(arc_length_[i]) + " mm) passes " +
                                 std::to_string(d) + " mm from segment " + std::to_string(j) +
                                 " (" + std::string(region_name(points_[j].region)) + ", " +
                                 std::to_string(arc_length_[j]) + " mm); their lumens overlap");
        }
    }
}

std::array<double, 8> ColonTube::region_lengths_mm() const {
    std::array<double, 8> lengths{};
    for (std::size_t i = 0; i + 1 < points_.size(); ++i)
        lengths[region_index(points_[i].region)] += arc_length_[i + 1] - arc_length_[i];
    return lengths;
}

std::pair<double, double> ColonTube::narrowest_radius_mm() const {
    std::size_t best = 0;
    for (std::size_t i = 1; i < points_.size(); ++i)
        if (points_[i].inner_radius_mm < points_[best].inner_radius_mm) best = i;
    return {points_[best].inner_radius_mm, arc_length_[best]};
}

std::size_t centerline_pieces(double length_mm, double spacing_mm, const std::string& field) {
    const double pieces = std::ceil(length_mm / spacing_mm);
    // Compared as doubles: a cast of a value beyond size_t's range is undefined.
    if (!std::isfinite(pieces) || pieces > static_cast<double>(kMaxCenterlinePoints))
        throw ModelError(field + ": " + std::to_string(length_mm) + " mm needs more than " +
                         std::to_string(kMaxCenterlinePoints) + " centerline points of " +
                         std::to_string(spacing_mm) + " mm");
    return pieces < 1.0 ? 1U : static_cast<std::size_t>(pieces);
}

std::vector<ColonPoint> sample_centerline(const std::vector<ColonPoint>& w, double spacing_mm) {
    require_positive(spacing_mm, "centerline spacing_mm");
    if (w.size() < 2) throw ModelError("centerline: needs at least 2 waypoints");
    std::vector<ColonPoint> out;
    const std::size_t n = w.size();
    for (std::size_t i = 0; i + 1 < n; ++i) {
        const Eigen::Vector3d p0 =
            i > 0 ? w[i - 1].position_mm : 2.0 * w[0].position_mm - w[1].position_mm;
        const Eigen::Vector3d p3 =
            i + 2 < n ? w[i + 2].position_mm : 2.0 * w[n - 1].position_mm - w[n - 2].position_mm;
        // Arc length of the span from 256 sub-samples, then samples at equal arc length.
        constexpr int kFine = 256;
        std::array<double, kFine + 1> s{};
        for (int k = 1; k <= kFine; ++k)
            s[static_cast<std::size_t>(k)] =
                s[static_cast<std::size_t>(k - 1)] +
                (catmull_rom(p0, w[i].position_mm, w[i + 1].position_mm, p3,
                             static_cast<double>(k) / kFine) -
                 catmull_rom(p0, w[i].position_mm, w[i + 1].position_mm, p3,
                             static_cast<double>(k - 1) / kFine))
                    .norm();
        const double span = s[kFine];
        const int pieces = static_cast<int>(
            centerline_pieces(span, spacing_mm, "centerline span " + std::to_string(i)));
        if (out.size() + static_cast<std::size_t>(pieces) > kMaxCenterlinePoints)
            throw ModelError("centerline: more than " + std::to_string(kMaxCenterlinePoints) +
                             " points (spacing_mm " + std::to_string(spacing_mm) + ")");
        std::size_t k = 0;
        for (int piece = 0; piece < pieces; ++piece) {
            const double target = span * piece / pieces;
            while (k + 1 < kFine && s[k + 1] < target)
                ++k;
            const double local = s[k + 1] > s[k] ? (target - s[k]) / (s[k + 1] - s[k]) : 0.0;
            const double t = (static_cast<double>(k) + local) / kFine;
            ColonPoint p;
            p.position_mm = catmull_rom(p0, w[i].position_mm, w[i + 1].position_mm, p3, t);
            p.inner_radius_mm = w[i].inner_radius_mm +
                                (w[i + 1].inner_radius_mm - w[i].inner_radius_mm) * (target / span);
            p.region = w[i].region;
            out.push_back(p);
        }
    }
    out.push_back(w.back());
    return out;
}

bool ColonTube::closest_point_near(const Eigen::Vector3d& point, double near_path_mm,
                                   double window_mm, double& path_mm, std::size_t& segment) const {
    if (!point.allFinite()) return false;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i + 1 < points_.size(); ++i) {
        const double a = arc_length_[i], b = arc_length_[i + 1];
        if (b < near_path_mm - window_mm || a > near_path_mm + window_mm) continue;
        const Eigen::Vector3d p = points_[i].position_mm, ab = points_[i + 1].position_mm - p;
        const double len2 = ab.squaredNorm();
        const double t = len2 > 0 ? std::clamp((point - p).dot(ab) / len2, 0.0, 1.0) : 0.0;
        const double d = (point - (p + t * ab)).norm();
        if (d < best) {
            best = d;
            path_mm = a + t * (b - a);
            segment = i;
        }
    }
    return std::isfinite(best);
}

}  // namespace scopekin::model
