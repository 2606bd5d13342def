#include "model/patient/patient.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numeric>

#include "model/colon/colon_beam.hpp"
#include "model/colon/straightened_path.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"
#include "model/patient/patient_random.hpp"
#include "model/scope/cf_q160l.hpp"

namespace scopekin::model {
namespace {

using Eigen::Vector3d;
using R = ColonRegion;

constexpr double kPi = M_PI;
constexpr double kDeg = M_PI / 180.0;
constexpr double kSpacing_mm = 10.0;  ///< longest chord of the sampled centerline

// ---- the family's ranges (model/patient/README.md, "The family") -------------------------------
struct Range {
    double lo, hi;
};
constexpr std::array<Range, 8> kRegionLength_mm{
    {{110, 170}, {250, 600}, {170, 250}, {55, 95}, {300, 700}, {55, 95}, {100, 180}, {50, 70}}};
constexpr std::array<Range, 8> kLumenRadius_mm{
    {{15, 22}, {11.5, 17}, {12, 18}, {14, 22}, {17, 27}, {17, 27}, {19, 28}, {20, 30}}};
constexpr Range kTotalLength_mm{1200, 1900};
constexpr Range kSigmoidLoopRadius_mm{25, 38};
constexpr Range kTiltN_deg{0, 30};
constexpr Range kTiltAlpha_deg{50, 80};
constexpr Range kSplenicAngle_deg{20, 60};
constexpr Range kHepaticAngle_deg{25, 70};
constexpr Range kSag_mm{60, 250};
constexpr Range kFriction{0.10, 0.45};
constexpr Range kWallModulusFactor{0.5, 1.5};
constexpr Range kMesenteryFactor{0.3, 3.0};
constexpr Range kEiFactor{0.85, 1.15};
constexpr Range kDistalLength_mm{80, 130};
constexpr Range kDistalFactor{0.5, 0.9};
constexpr Range kTransverseWidth_mm{100, 350};
constexpr double kAlphaProneShare = 0.2;
constexpr double kDescendingMobileShare = 0.1;
constexpr double kAscendingMobileShare = 0.1;
constexpr double kDistalSectionShare = 0.5;
constexpr double kLowestY_mm =
    20.0;  ///< nothing lower than 20 mm cranial of the anus but the rectum

// ---- shape constants (model/patient/README.md, "The shape") ------------------------------------
constexpr double kSigmoidEntryArc_mm = 40.0;  ///< rectosigmoid junction to the loop's first limb
constexpr double kSigmoidExitArc_mm = 45.0;   ///< each of the two arcs into the descending colon
constexpr double kTransverseBottomRadius_mm = 40.0;
constexpr double kMinHepaticLimb_mm = 40.0;
constexpr double kBlend_mm =
    30.0;  ///< the lumen radius changes linearly over a region's first 30 mm

constexpr std::array<const char*, 4> kMobileNames{"sigmoid", "transverse", "descending",
                                                  "ascending"};

std::size_t idx(ColonRegion r) {
    return static_cast<std::size_t>(r);
}

Vector3d unit(double x, double y, double z) {
    return Vector3d(x, y, z).normalized();
}

/// `v` without its component along the unit vector `n`, normalised.
Vector3d orthogonal(const Vector3d& v, const Vector3d& n) {
    return (v - v.dot(n) * n).normalized();
}

/// Headings (unit vectors) of the construction.
const Vector3d kRectumStart = unit(0, 1, -0.4);   // cranial, posterior along the sacrum
const Vector3d kRectumEnd = unit(0, 1, 0.35);     // out of the pelvis, anterior
const Vector3d kLoopLimb = unit(-0.3, 1, 0.5);    // the sigmoid loop's first limb
const Vector3d kSigmoidTurn = unit(1, 0, -0.25);  // the sigmoid-descending junction's bottom
const Vector3d kDescending = unit(0.05, 1, -0.1);
const Vector3d kAscending = unit(-0.05, -1, -0.1);

/// A centerline drawn as chords of at most kSpacing_mm: straight runs and circular arcs whose
/// chords add up to the run's or arc's length exactly.
class Turtle {
public:
    Turtle() : heading_(kRectumStart) { points_.push_back(Vector3d::Zero()); }

    void straight(double length_mm, ColonRegion region) {
        if (!(length_mm > 0.0)) return;
        const auto n = centerline_pieces(length_mm, kSpacing_mm, "patient straight run");
        for (std::size_t i = 0; i < n; ++i)
            step(length_mm / static_cast<double>(n), region);
    }

    /// Turns the heading by `angle` about the unit `axis` over `length_mm` (radius length / angle):
    /// n equal chords, each between two half-turns of angle / (2 n).
    void arc_about(const Vector3d& axis, double angle, double length_mm, ColonRegion region) {
        if (!(length_mm > 0.0)) return;
        const auto n = centerline_pieces(length_mm, kSpacing_mm, "patient arc");
        const Eigen::AngleAxisd half(angle / (2.0 * static_cast<double>(n)), axis);
        for (std::size_t i = 0; i < n; ++i) {
            heading_ = (half * heading_).normalized();
            step(length_mm / static_cast<double>(n), region);
            heading_ = (half * heading_).normalized();
        }
    }

    /// Arc from the current heading to `target` (unit, not opposite) over `length_mm`.
    void arc_to(const Vector3d& target, double length_mm, ColonRegion region) {
        const Vector3d cross = heading_.cross(target);
        const double angle = std::atan2(cross.norm(), heading_.dot(target));
        if (cross.norm() < 1e-12) {
            straight(length_mm, region);
        } else {
            arc_about(cross.normalized(), angle, length_mm, region);
        }
        heading_ = target;
    }

    const Vector3d& heading() const { return heading_; }
    const std::vector<Vector3d>& points() const { return points_; }
    const std::vector<ColonRegion>& regions() const { return regions_; }

private:
    void step(double chord_mm, ColonRegion region) {
        points_.push_back(points_.back() + chord_mm * heading_);
        regions_.push_back(region);
    }
    Vector3d heading_;
    std::vector<Vector3d> points_;
    std::vector<ColonRegion> regions_;  ///< region of chord i (points i .. i + 1)
};

double turn_angle(const Vector3d& a, const Vector3d& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// The sigmoid loop's turn direction o (unit, orthogonal to the first limb): towards the
/// patient's left, tilted anteriorly out of the frontal plane by the loop tilt.
Vector3d loop_offset(const PatientSpec& p) {
    const Vector3d lateral = orthogonal(Vector3d::UnitX(), kLoopLimb);
    Vector3d anterior = kLoopLimb.cross(lateral).normalized();
    if (anterior.z() < 0.0) anterior = -anterior;
    const double tilt = p.sigmoid_loop_tilt_deg * kDeg;
    return std::cos(tilt) * lateral + std::sin(tilt) * anterior;
}

/// The transverse colon's first limb (interior angle `splenic` with the descending colon,
/// towards the right and anterior) and last limb (interior angle `hepatic` with the ascending).
std::pair<Vector3d, Vector3d> transverse_limbs(const PatientSpec& p) {
    const double a1 = p.splenic_flexure_angle_deg * kDeg, a2 = p.hepatic_flexure_angle_deg * kDeg;
    const Vector3d right = orthogonal(unit(-1, 0, 0.8), kDescending);
    const Vector3d first = std::cos(a1) * (-kDescending) + std::sin(a1) * right;
    const Vector3d left = orthogonal(unit(1, 0, 0.8), kAscending);
    const Vector3d last = -(std::cos(a2) * kAscending + std::sin(a2) * left);
    return {first.normalized(), last.normalized()};
}

double sigmoid_fixed_length_mm(const PatientSpec& p) {
    return kSigmoidEntryArc_mm + kPi * p.sigmoid_loop_radius_mm + 2.0 * kSigmoidExitArc_mm;
}

double transverse_bottom_length_mm(const PatientSpec& p) {
    const auto [first, last] = transverse_limbs(p);
    return kTransverseBottomRadius_mm * turn_angle(first, last);
}

/// Longest first transverse limb: the last limb keeps kMinHepaticLimb_mm.
double max_first_limb_mm(const PatientSpec& p) {
    return p.region_length_mm[idx(R::transverse)] - transverse_bottom_length_mm(p) -
           kMinHepaticLimb_mm;
}

/// The centerline with a first transverse limb of `first_limb_mm`; regions per chord.
Turtle build(const PatientSpec& p, double first_limb_mm) {
    const auto& len = p.region_length_mm;
    Turtle t;
    // Rectum: along the sacrum, then out of the pelvis.
    t.straight(0.45 * len[idx(R::rectum)], R::rectum);
    t.arc_to(kRectumEnd, 0.55 * len[idx(R::rectum)], R::rectum);
    // Sigmoid: an entry arc, the loop (limb, half turn, limb back: its limbs' length moves
    // nothing downstream), two arcs into the descending colon.
    const double limb = 0.5 * (len[idx(R::sigmoid)] - sigmoid_fixed_length_mm(p));
    t.arc_to(kLoopLimb, kSigmoidEntryArc_mm, R::sigmoid);
    t.straight(limb, R::sigmoid);
    const Vector3d axis = kLoopLimb.cross(loop_offset(p)).normalized();
    t.arc_about(axis, kPi, kPi * p.sigmoid_loop_radius_mm, R::sigmoid);
    t.straight(limb, R::sigmoid);
    t.arc_to(kSigmoidTurn, kSigmoidExitArc_mm, R::sigmoid);
    t.arc_to(kDescending, kSigmoidExitArc_mm, R::sigmoid);
    t.straight(len[idx(R::descending)], R::descending);
    // Splenic flexure, the transverse colon hanging between its two limbs, hepatic flexure.
    const auto [first, last] = transverse_limbs(p);
    t.arc_to(first, len[idx(R::splenic_flexure)], R::splenic_flexure);
    t.straight(first_limb_mm, R::transverse);
    const double bottom = transverse_bottom_length_mm(p);
    t.arc_to(last, bottom, R::transverse);
    t.straight(len[idx(R::transverse)] - first_limb_mm - bottom, R::transverse);
    t.arc_to(kAscending, len[idx(R::hepatic_flexure)], R::hepatic_flexure);
    t.straight(len[idx(R::ascending)], R::ascending);
    t.straight(len[idx(R::cecum)], R::cecum);
    return t;
}

/// First and one-past-last point index of the chords of `region`.
std::pair<std::size_t, std::size_t> region_points(const std::vector<ColonRegion>& regions,
                                                  ColonRegion region) {
    const auto first = std::find(regions.begin(), regions.end(), region);
    const auto last =
        std::find_if(first, regions.end(), [&](ColonRegion r) { return r != region; });
    return {static_cast<std::size_t>(first - regions.begin()),
            static_cast<std::size_t>(last - regions.begin())};
}

/// Depth of the transverse colon's lowest point below its first point (y, mm).
double sag_of(const Turtle& t) {
    const auto [begin, end] = region_points(t.regions(), R::transverse);
    double lowest = t.points()[begin].y();
    for (std::size_t i = begin; i <= end; ++i)
        lowest = std::min(lowest, t.points()[i].y());
    return t.points()[begin].y() - lowest;
}

/// The first limb that gives the patient's sag (bisection; the sag grows with the limb, as the
/// limb only moves the bottom and the last limb down). NaN when no limb in [0, max] gives it.
double first_limb_for_sag(const PatientSpec& p) {
    double lo = 0.0, hi = max_first_limb_mm(p);
    if (!(hi >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
    if (sag_of(build(p, lo)) > p.transverse_sag_mm || sag_of(build(p, hi)) < p.transverse_sag_mm)
        return std::numeric_limits<double>::quiet_NaN();
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (sag_of(build(p, mid)) < p.transverse_sag_mm ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

std::string range_text(const Range& r) {
    std::string text = "[";  // appended, not "[" + ...: GCC 12's -Wrestrict false positive
    text += number_text(r.lo);
    text += ", ";
    text += number_text(r.hi);
    text += "]";
    return text;
}

void require_range(double v, const Range& r, const std::string& field) {
    if (!(v >= r.lo && v <= r.hi))
        throw ModelError(field + ": " + number_text(v) + " must be in " + range_text(r));
}

using FieldOf = std::function<std::string(const std::string&)>;

/// Every parameter inside the family's range; names the JSON field (model/patient/README.md).
void check_ranges(const PatientSpec& p, const FieldOf& field) {
    for (std::size_t i = 0; i < 8; ++i) {
        const std::string name(region_name(kColonRegionsInOrder[i]));
        require_range(p.region_length_mm[i], kRegionLength_mm[i],
                      field("colon.region_lengths_mm." + name));
        require_range(p.lumen_radius_mm[i], kLumenRadius_mm[i],
                      field("colon.lumen_radius_mm." + name));
    }
    require_range(p.total_length_mm(), kTotalLength_mm,
                  field("colon.region_lengths_mm") + " (their sum)");
    require_range(p.sigmoid_loop_radius_mm, kSigmoidLoopRadius_mm,
                  field("colon.sigmoid_loop_radius_mm"));
    require_range(p.sigmoid_loop_tilt_deg,
                  p.sigmoid_shape == SigmoidShape::n_prone ? kTiltN_deg : kTiltAlpha_deg,
                  field("colon.sigmoid_loop_tilt_deg") + " (" +
                      std::string(sigmoid_shape_name(p.sigmoid_shape)) + ")");
    require_range(p.splenic_flexure_angle_deg, kSplenicAngle_deg,
                  field("colon.splenic_flexure_angle_deg"));
    require_range(p.hepatic_flexure_angle_deg, kHepaticAngle_deg,
                  field("colon.hepatic_flexure_angle_deg"));
    require_range(p.transverse_sag_mm, kSag_mm, field("colon.transverse_sag_mm"));
    require_range(p.friction_coefficient, kFriction, field("mechanics.friction_coefficient"));
    require_range(p.wall_modulus_factor, kWallModulusFactor,
                  field("mechanics.wall_modulus_factor"));
    for (std::size_t i = 0; i < 4; ++i)
        require_range(p.mesentery_factor[i], kMesenteryFactor,
                      field(std::string("mechanics.mesentery_factor.") + kMobileNames[i]));
    require_range(p.ei_factor, kEiFactor, field("scope.ei_factor"));
    if (p.distal_section_length_mm != 0.0 || p.distal_section_factor != 1.0) {
        require_range(p.distal_section_length_mm, kDistalLength_mm,
                      field("scope.distal_section_length_mm") + " (0 for none)");
        require_range(p.distal_section_factor, kDistalFactor,
                      field("scope.distal_section_factor") + " (1 for none)");
    }
}

/// The sags (kSag_mm) for which the transverse colon is kTransverseWidth_mm wide and nothing
/// but the rectum lies below kLowestY_mm: the first limb scanned in 64 steps from 0 to its
/// longest (width and height are linear in it, so the feasible limbs form one interval).
/// {NaN, NaN} when there are none.
std::pair<double, double> feasible_sag_range(const PatientSpec& p) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double longest = max_first_limb_mm(p);
    if (!(longest >= 0.0)) return {nan, nan};
    double shallowest = nan, deepest = nan;
    for (int k = 0; k <= 64; ++k) {
        const Turtle t = build(p, longest * k / 64.0);
        const auto& pts = t.points();
        const auto [t0, t1] = region_points(t.regions(), R::transverse);
        const double width = std::abs(pts[t1].x() - pts[t0].x());
        const auto [r0, r1] = region_points(t.regions(), R::rectum);
        double lowest = std::numeric_limits<double>::infinity();
        for (std::size_t i = r1 + 1; i < pts.size(); ++i)
            lowest = std::min(lowest, pts[i].y());
        const double sag = sag_of(t);
        (void)r0;
        if (width < kTransverseWidth_mm.lo || width > kTransverseWidth_mm.hi ||
            lowest < kLowestY_mm || sag < kSag_mm.lo || sag > kSag_mm.hi)
            continue;
        if (!(sag >= shallowest)) shallowest = sag;
        if (!(sag <= deepest)) deepest = sag;
    }
    return {shallowest, deepest};
}

/// One draw from the family, in the documented order (model/patient/README.md).
PatientSpec draw_once(PatientRandom& r, std::uint64_t seed) {
    PatientSpec p;
    p.seed = seed;
    auto& len = p.region_length_mm;
    len[idx(R::rectum)] = r.uniform(110, 170);
    len[idx(R::sigmoid)] = r.truncated_normal(400, 130, 250, 600);
    len[idx(R::descending)] = r.uniform(170, 250);
    len[idx(R::splenic_flexure)] = r.uniform(55, 95);
    len[idx(R::transverse)] = r.truncated_normal(470, 130, 300, 700);
    len[idx(R::hepatic_flexure)] = r.uniform(55, 95);
    len[idx(R::ascending)] = r.uniform(100, 180);
    len[idx(R::cecum)] = r.uniform(50, 70);
    for (std::size_t i = 0; i < 8; ++i)
        p.lumen_radius_mm[i] = r.uniform(kLumenRadius_mm[i].lo, kLumenRadius_mm[i].hi);
    p.sigmoid_shape =
        r.bernoulli(kAlphaProneShare) ? SigmoidShape::alpha_prone : SigmoidShape::n_prone;
    p.sigmoid_loop_radius_mm = r.uniform(kSigmoidLoopRadius_mm.lo, kSigmoidLoopRadius_mm.hi);
    const Range tilt = p.sigmoid_shape == SigmoidShape::n_prone ? kTiltN_deg : kTiltAlpha_deg;
    p.sigmoid_loop_tilt_deg = r.uniform(tilt.lo, tilt.hi);
    p.splenic_flexure_angle_deg = r.uniform(kSplenicAngle_deg.lo, kSplenicAngle_deg.hi);
    p.hepatic_flexure_angle_deg = r.uniform(kHepaticAngle_deg.lo, kHepaticAngle_deg.hi);
    // The sag: uniform over the sags whose transverse colon keeps the width and the lowest point
    // plausible (feasible_sag_range), within kSag_mm; NaN when none does.
    const auto [shallowest, deepest] = feasible_sag_range(p);
    p.transverse_sag_mm = shallowest + (deepest - shallowest) * r.unit();
    p.friction_coefficient = r.uniform(kFriction.lo, kFriction.hi);
    p.wall_modulus_factor = r.uniform(kWallModulusFactor.lo, kWallModulusFactor.hi);
    for (double& f : p.mesentery_factor)
        f = r.log_uniform(kMesenteryFactor.lo, kMesenteryFactor.hi);
    p.descending_mobile = r.bernoulli(kDescendingMobileShare);
    p.ascending_mobile = r.bernoulli(kAscendingMobileShare);
    p.ei_factor = r.uniform(kEiFactor.lo, kEiFactor.hi);
    if (r.bernoulli(kDistalSectionShare)) {
        p.distal_section_length_mm = r.uniform(kDistalLength_mm.lo, kDistalLength_mm.hi);
        p.distal_section_factor = r.uniform(kDistalFactor.lo, kDistalFactor.hi);
    }
    return p;
}

}  // namespace

double PatientSpec::total_length_mm() const {
    return std::accumulate(region_length_mm.begin(), region_length_mm.end(), 0.0);
}

std::string_view sigmoid_shape_name(SigmoidShape shape) {
    return shape == SigmoidShape::n_prone ? "n_prone" : "alpha_prone";
}

std::uint64_t patient_sub_seed(std::uint64_t seed, std::size_t k) {
    std::uint64_t z = seed + static_cast<std::uint64_t>(k) * 0x9E3779B97F4A7C15ULL;
    z += 0x9E3779B97F4A7C15ULL;  // splitmix64 (Steele, Lea & Flood 2014)
    z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31U);
}

std::vector<ColonPoint> patient_centerline(const PatientSpec& p) {
    const double limb = first_limb_for_sag(p);
    if (!std::isfinite(limb))
        throw ModelError("patient " + std::to_string(p.seed) + ": a transverse colon of " +
                         number_text(p.region_length_mm[idx(R::transverse)]) + " mm cannot sag " +
                         number_text(p.transverse_sag_mm) +
                         " mm with these flexure angles (its last limb would be shorter than " +
                         number_text(kMinHepaticLimb_mm) + " mm)");
    const Turtle t = build(p, limb);
    const auto& positions = t.points();
    const auto& regions = t.regions();
    std::vector<ColonPoint> points(positions.size());
    double region_start = 0.0, arc = 0.0;
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (i > 0) arc += (positions[i] - positions[i - 1]).norm();
        const ColonRegion region = i < regions.size() ? regions[i] : R::cecum;
        if (i > 0 && i < regions.size() && regions[i] != regions[i - 1]) region_start = arc;
        double radius = p.lumen_radius_mm[idx(region)];
        if (region != R::rectum && arc - region_start < kBlend_mm) {
            const double before = p.lumen_radius_mm[idx(region) - 1];
            radius = before + (radius - before) * (arc - region_start) / kBlend_mm;
        }
        points[i] = {positions[i], radius, region};
    }
    return points;
}

ColonTube patient_colon(const PatientSpec& p, double scope_radius_mm) {
    return ColonTube("patient " + std::to_string(p.seed), patient_centerline(p), scope_radius_mm);
}

std::array<ColonRegionProperties, 8> patient_colon_properties(const PatientSpec& p) {
    std::array<ColonRegionProperties, 8> props = default_colon_properties();
    const double mesentery = default_region_properties(R::sigmoid).mesentery_stiffness_N_per_mm2;
    auto hang = [&](ColonRegion r, MobileRegion factor) {
        props[idx(r)].attachment = ColonAttachment::mesentery;
        props[idx(r)].mesentery_stiffness_N_per_mm2 =
            mesentery * p.mesentery_factor[static_cast<std::size_t>(factor)];
    };
    for (auto& q : props)
        q.young_modulus_kPa *= p.wall_modulus_factor;
    hang(R::sigmoid, MobileRegion::sigmoid);
    hang(R::transverse, MobileRegion::transverse);
    if (p.descending_mobile) hang(R::descending, MobileRegion::descending);
    if (p.ascending_mobile) {
        hang(R::ascending, MobileRegion::ascending);
        hang(R::cecum, MobileRegion::ascending);
    }
    return props;
}

std::pair<double, std::size_t> smallest_bend_radius_mm(const std::vector<ColonPoint>& points) {
    double smallest = std::numeric_limits<double>::infinity();
    std::size_t at = 0;
    for (std::size_t i = 1; i + 1 < points.size(); ++i) {
        const Vector3d a = points[i - 1].position_mm, b = points[i].position_mm,
                       c = points[i + 1].position_mm;
        const double twice_area = (b - a).cross(c - a).norm();
        if (twice_area < 1e-12) continue;
        // Circumradius abc / (4 area).
        const double r = (b - a).norm() * (c - b).norm() * (c - a).norm() / (2.0 * twice_area);
        if (r < smallest) {
            smallest = r;
            at = i;
        }
    }
    return {smallest, at};
}

PatientMeasures measure_patient(const PatientSpec& p) {
    const std::vector<ColonPoint> points = patient_centerline(p);
    std::vector<ColonRegion> regions;
    for (std::size_t i = 0; i + 1 < points.size(); ++i)
        regions.push_back(points[i].region);
    PatientMeasures m;
    const auto [s0, s1] = region_points(regions, R::sigmoid);
    m.sigmoid_chord_mm = (points[s1].position_mm - points[s0].position_mm).norm();
    m.sigmoid_redundancy = 1.0 - m.sigmoid_chord_mm / p.region_length_mm[idx(R::sigmoid)];
    const auto [t0, t1] = region_points(regions, R::transverse);
    double lowest = points[t0].position_mm.y();
    for (std::size_t i = t0; i <= t1; ++i)
        lowest = std::min(lowest, points[i].position_mm.y());
    m.transverse_sag_mm = points[t0].position_mm.y() - lowest;
    m.transverse_width_mm = std::abs(points[t1].position_mm.x() - points[t0].position_mm.x());
    auto direction = [&](std::size_t i) {
        return (points[i + 1].position_mm - points[i].position_mm).normalized();
    };
    // Interior angle between the run before a flexure and the run after it.
    const auto [d0, d1] = region_points(regions, R::descending);
    const auto [a0, a1] = region_points(regions, R::ascending);
    m.splenic_flexure_angle_deg = turn_angle(-direction(d1 - 1), direction(t0)) / kDeg;
    m.hepatic_flexure_angle_deg = turn_angle(-direction(t1 - 1), direction(a0)) / kDeg;
    (void)d0;
    (void)a1;
    m.smallest_bend_radius_mm = smallest_bend_radius_mm(points).first;
    const auto [r0, r1] = region_points(regions, R::rectum);
    m.lowest_y_mm = std::numeric_limits<double>::infinity();
    for (std::size_t i = r1 + 1; i < points.size(); ++i)
        m.lowest_y_mm = std::min(m.lowest_y_mm, points[i].position_mm.y());
    (void)r0;
    m.straightened_path_mm = straightened_path_mm(points, patient_colon_properties(p));
    return m;
}

std::string patient_problem(const PatientSpec& p, double scope_radius_mm) {
    try {
        check_ranges(p, [](const std::string& f) { return f; });
        const PatientMeasures m = measure_patient(p);  // throws if the sag is impossible
        if (!(m.transverse_width_mm >= kTransverseWidth_mm.lo &&
              m.transverse_width_mm <= kTransverseWidth_mm.hi))
            return "transverse colon " + number_text(m.transverse_width_mm) +
                   " mm wide (flexure to flexure), outside " + range_text(kTransverseWidth_mm);
        if (m.lowest_y_mm < kLowestY_mm)
            return "colon reaches " + number_text(m.lowest_y_mm) +
                   " mm (y) above the anus, lower than " + number_text(kLowestY_mm) + " mm";
        if (m.smallest_bend_radius_mm < kMinPatientBendRadius_mm)
            return "bend of radius " + number_text(m.smallest_bend_radius_mm) +
                   " mm, tighter than " + number_text(kMinPatientBendRadius_mm) + " mm";
        (void)patient_colon(p, scope_radius_mm);
    } catch (const ModelError& e) {
        return e.what();
    }
    return "";
}

PatientSpec draw_patient(std::uint64_t seed, std::vector<std::string>& refusals) {
    refusals.clear();
    for (std::size_t k = 0; k < kMaxPatientDraws; ++k) {
        PatientRandom random(patient_sub_seed(seed, k));
        PatientSpec p = draw_once(random, seed);
        p.redraws = k;
        const std::string problem =
            std::isfinite(p.transverse_sag_mm)
                ? patient_problem(p, cf_q160l::kRadius_mm)
                : "no transverse sag in " + range_text(kSag_mm) +
                      " mm keeps the transverse colon " + range_text(kTransverseWidth_mm) +
                      " mm wide and the colon above y = " + number_text(kLowestY_mm) + " mm";
        if (problem.empty()) return p;
        refusals.push_back(problem);
    }
    throw ModelError("patient seed " + std::to_string(seed) + ": no acceptable draw in " +
                     std::to_string(kMaxPatientDraws) + " attempts (last: " + refusals.back() +
                     ")");
}

PatientSpec draw_patient(std::uint64_t seed) {
    std::vector<std::string> refusals;
    return draw_patient(seed, refusals);
}

// ---- JSON ---------------------------------------------------------------------------------------

namespace {

nlohmann::ordered_json per_region(const std::array<double, 8>& values) {
    nlohmann::ordered_json o = nlohmann::ordered_json::object();
    for (std::size_t i = 0; i < 8; ++i)
        o[std::string(region_name(kColonRegionsInOrder[i]))] = values[i];
    return o;
}

const char* attachment_text(bool mobile) {
    return mobile ? "mesentery" : "fixed";
}

std::array<double, 8> read_per_region(const io::JsonObject& o) {
    o.allow_only({"rectum", "sigmoid", "descending", "splenic_flexure", "transverse",
                  "hepatic_flexure", "ascending", "cecum"});
    std::array<double, 8> values{};
    for (std::size_t i = 0; i < 8; ++i) {
        const std::string name(region_name(kColonRegionsInOrder[i]));
        values[i] = o.number(name.c_str());
    }
    return values;
}

bool read_attachment(const io::JsonObject& o, const char* key) {
    const std::string a = o.string(key);
    if (a != "fixed" && a != "mesentery")
        throw ModelError(o.field(key) + ": unknown attachment " + io::quote_text(a) +
                         " (known: fixed, mesentery)");
    return a == "mesentery";
}

}  // namespace

std::uint64_t read_patient_seed(const io::JsonObject& o, const char* key) {
    const nlohmann::json& v = o.raw(key);
    if (v.is_number_unsigned()) return v.get<std::uint64_t>();
    if (v.is_number_integer() && v.get<std::int64_t>() >= 0)
        return static_cast<std::uint64_t>(v.get<std::int64_t>());
    throw ModelError(o.field(key) + ": expected a whole number from 0 to 2^64 - 1, got " +
                     io::json_excerpt(v));
}

nlohmann::ordered_json patient_to_json(const PatientSpec& p) {
    nlohmann::ordered_json j;
    j["seed"] = p.seed;
    j["redraws"] = p.redraws;
    j["colon"] = {{"region_lengths_mm", per_region(p.region_length_mm)},
                  {"lumen_radius_mm", per_region(p.lumen_radius_mm)},
                  {"sigmoid_shape", std::string(sigmoid_shape_name(p.sigmoid_shape))},
                  {"sigmoid_loop_radius_mm", p.sigmoid_loop_radius_mm},
                  {"sigmoid_loop_tilt_deg", p.sigmoid_loop_tilt_deg},
                  {"splenic_flexure_angle_deg", p.splenic_flexure_angle_deg},
                  {"hepatic_flexure_angle_deg", p.hepatic_flexure_angle_deg},
                  {"transverse_sag_mm", p.transverse_sag_mm}};
    nlohmann::ordered_json factors = nlohmann::ordered_json::object();
    for (std::size_t i = 0; i < 4; ++i)
        factors[kMobileNames[i]] = p.mesentery_factor[i];
    j["mechanics"] = {{"friction_coefficient", p.friction_coefficient},
                      {"wall_modulus_factor", p.wall_modulus_factor},
                      {"mesentery_factor", factors},
                      {"descending_attachment", attachment_text(p.descending_mobile)},
                      {"ascending_attachment", attachment_text(p.ascending_mobile)}};
    j["scope"] = {{"ei_factor", p.ei_factor},
                  {"distal_section_length_mm", p.distal_section_length_mm},
                  {"distal_section_factor", p.distal_section_factor}};
    j["derived"] = {{"total_length_mm", p.total_length_mm()}};
    return j;
}

PatientSpec read_patient(const nlohmann::json& document, const std::string& path) {
    const io::JsonObject root(document, path);
    root.allow_only({"seed", "redraws", "colon", "mechanics", "scope", "derived"});
    PatientSpec p;
    p.seed = read_patient_seed(root, "seed");
    p.redraws = root.index("redraws");

    const io::JsonObject colon = root.object("colon");
    colon.allow_only({"region_lengths_mm", "lumen_radius_mm", "sigmoid_shape",
                      "sigmoid_loop_radius_mm", "sigmoid_loop_tilt_deg",
                      "splenic_flexure_angle_deg", "hepatic_flexure_angle_deg",
                      "transverse_sag_mm"});
    p.region_length_mm = read_per_region(colon.object("region_lengths_mm"));
    p.lumen_radius_mm = read_per_region(colon.object("lumen_radius_mm"));
    const std::string shape = colon.string("sigmoid_shape");
    if (shape != "n_prone" && shape != "alpha_prone")
        throw ModelError(colon.field("sigmoid_shape") + ": unknown shape " + io::quote_text(shape) +
                         " (known: n_prone, alpha_prone)");
    p.sigmoid_shape = shape == "n_prone" ? SigmoidShape::n_prone : SigmoidShape::alpha_prone;
    p.sigmoid_loop_radius_mm = colon.number("sigmoid_loop_radius_mm");
    p.sigmoid_loop_tilt_deg = colon.number("sigmoid_loop_tilt_deg");
    p.splenic_flexure_angle_deg = colon.number("splenic_flexure_angle_deg");
    p.hepatic_flexure_angle_deg = colon.number("hepatic_flexure_angle_deg");
    p.transverse_sag_mm = colon.number("transverse_sag_mm");

    const io::JsonObject mech = root.object("mechanics");
    mech.allow_only({"friction_coefficient", "wall_modulus_factor", "mesentery_factor",
                     "descending_attachment", "ascending_attachment"});
    p.friction_coefficient = mech.number("friction_coefficient");
    p.wall_modulus_factor = mech.number("wall_modulus_factor");
    const io::JsonObject factors = mech.object("mesentery_factor");
    factors.allow_only({"sigmoid", "transverse", "descending", "ascending"});
    for (std::size_t i = 0; i < 4; ++i)
        p.mesentery_factor[i] = factors.number(kMobileNames[i]);
    p.descending_mobile = read_attachment(mech, "descending_attachment");
    p.ascending_mobile = read_attachment(mech, "ascending_attachment");

    const io::JsonObject scope = root.object("scope");
    scope.allow_only({"ei_factor", "distal_section_length_mm", "distal_section_factor"});
    p.ei_factor = scope.number("ei_factor");
    p.distal_section_length_mm = scope.number("distal_section_length_mm");
    p.distal_section_factor = scope.number("distal_section_factor");

    check_ranges(p, [&](const std::string& f) { return root.field(f); });
    if (root.has("derived")) {
        const io::JsonObject derived = root.object("derived");
        derived.allow_only({"total_length_mm"});
        const double total = derived.number("total_length_mm");
        if (!(std::abs(total - p.total_length_mm()) <= 1e-6 * p.total_length_mm()))
            throw ModelError(derived.field("total_length_mm") + ": " + number_text(total) +
                             " mm is not the sum of colon.region_lengths_mm (" +
                             number_text(p.total_length_mm()) +
                             " mm); correct it or leave 'derived' out");
    }
    // The geometry: a sag the transverse colon can make, then every check of a drawn patient.
    const std::string problem = patient_problem(p, cf_q160l::kRadius_mm);
    if (!problem.empty())
        throw ModelError(root.path() + (root.path().back() == ':' ? " " : ": ") +
                         "not an acceptable patient: " + problem);
    return p;
}

PatientSpec read_patient_file(const std::string& filename) {
    return read_patient(io::parse_json_file(filename), filename + ":");
}

}  // namespace scopekin::model
