#include "model/colon/colon_beam.hpp"

#include <cmath>
#include <string>

#include "model/model_error.hpp"

namespace scopekin::model {

BeamSection hollow_colon_section(double r, double t, double e_kPa) {
    require_positive(r, "colon inner_radius_mm");
    require_positive(t, "colon wall_thickness_mm");
    require_positive(e_kPa, "colon young_modulus_kPa");
    const double e = e_kPa * 1e-3;  // kPa -> N/mm^2 (MPa)
    const double ro = r + t;
    const double area = M_PI * (ro * ro - r * r);
    const double second_moment = M_PI / 4.0 * (ro * ro * ro * ro - r * r * r * r);
    const double shear_modulus = e / (2.0 * (1.0 + kColonPoissonRatio));
    BeamSection s;
    s.axial_stiffness_N = e * area;
    s.bending_stiffness_y_Nmm2 = e * second_moment;
    s.bending_stiffness_z_Nmm2 = e * second_moment;
    s.torsional_stiffness_Nmm2 = shear_modulus * 2.0 * second_moment;
    s.shear_stiffness_y_N = kThinTubeShearCorrection * shear_modulus * area;
    s.shear_stiffness_z_N = s.shear_stiffness_y_N;
    return s;  // no mass: Eq. 4.16 is static
}

std::array<ColonRegionProperties, 8> default_colon_properties() {
    std::array<ColonRegionProperties, 8> p{};
    for (std::size_t i = 0; i < 8; ++i)
        p[i] = default_region_properties(kColonRegionsInOrder[i]);
    return p;
}

ColonStructure build_colon_structure(const ColonTube& tube,
                                     const std::array<ColonRegionProperties, 8>& properties) {
    for (std::size_t i = 0; i < 8; ++i) {
        const std::string where =
            "colon region " + std::string(region_name(kColonRegionsInOrder[i])) + ": ";
        require_positive(properties[i].young_modulus_kPa, where + "young_modulus_kPa");
        require_positive(properties[i].wall_thickness_mm, where + "wall_thickness_mm");
        require_non_negative(properties[i].mesentery_stiffness_N_per_mm2,
                             where + "mesentery_stiffness_N_per_mm2");
    }
    const auto& points = tube.points();
    std::vector<Eigen::Vector3d> nodes;
    std::vector<BeamSection> sections;
    for (std::size_t i = 0; i < points.size(); ++i) {
        nodes.push_back(points[i].position_mm);
        if (i + 1 < points.size()) {
            const ColonRegionProperties& p = properties[static_cast<std::size_t>(points[i].region)];
            const double radius = 0.5 * (points[i].inner_radius_mm + points[i + 1].inner_radius_mm);
            sections.push_back(
                hollow_colon_section(radius, p.wall_thickness_mm, p.young_modulus_kPa));
        }
    }
    ColonStructure c{ScopeBeam(std::move(nodes), std::move(sections)), {}, {}, {}};
    c.mobile.assign(points.size(), false);
    for (std::size_t i = 0; i < points.size(); ++i) {
        // A node belongs to a mobile region only if both segments touching it do (region borders
        // and the ends stay with the fixed neighbour).
        const ColonRegion before = i > 0 ? points[i - 1].region : points[i].region;
        const ColonRegion after = points[i].region;
        const auto& pb = properties[static_cast<std::size_t>(before)];
        const auto& pa = properties[static_cast<std::size_t>(after)];
        const bool mobile = i > 0 && i + 1 < points.size() &&
                            pb.attachment == ColonAttachment::mesentery &&
                            pa.attachment == ColonAttachment::mesentery;
        c.mobile[i] = mobile;
        if (!mobile) {
            NodeSupport clamp;
            clamp.node = i;
            c.supports.push_back(clamp);
            continue;
        }
        // Mesentery: stiffness per unit length times the node's share of the centerline.
        const double share = 0.5 * (tube.arc_length_mm(i + 1) - tube.arc_length_mm(i - 1));
        c.loads.springs.push_back(
            {i, points[i].position_mm, pa.mesentery_stiffness_N_per_mm2 * share});
    }
    return c;
}

}  // namespace scopekin::model
