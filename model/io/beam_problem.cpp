#include "model/io/beam_problem.hpp"

#include <cmath>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"
#include "model/scope/cf_q160l.hpp"

namespace scopekin::model::io {
namespace {

BeamSection read_section(const nlohmann::json& value, const std::string& path) {
    if (value.is_string()) {
        if (value.get<std::string>() == "cf_q160l") return cf_q160l::section();
        throw ModelError(path + ": unknown section name " + quote_text(value.get<std::string>()) +
                         " (known: cf_q160l)");
    }
    const JsonObject o(value, path);
    o.allow_only({"EA_N", "EI_Nmm2", "EI_y_Nmm2", "EI_z_Nmm2", "GJ_Nmm2", "kappa_GA_N",
                  "weight_per_length_N_per_mm", "radius_mm"});
    BeamSection s;
    const double ei = o.number_or("EI_Nmm2", std::nan(""));
    s.bending_stiffness_y_Nmm2 = o.number_or("EI_y_Nmm2", ei);
    s.bending_stiffness_z_Nmm2 = o.number_or("EI_z_Nmm2", ei);
    s.axial_stiffness_N = o.number("EA_N");
    s.torsional_stiffness_Nmm2 = o.number("GJ_Nmm2");
    s.shear_stiffness_y_N = s.shear_stiffness_z_N = o.number_or("kappa_GA_N", INFINITY);
    const double weight = o.number_or("weight_per_length_N_per_mm", 0.0);
    require_non_negative(weight, o.field("weight_per_length_N_per_mm"));
    s.mass_per_length_t_per_mm = weight / kGravity_mm_per_s2;
    const double radius = o.number_or("radius_mm", 0.0);
    require_non_negative(radius, o.field("radius_mm"));
    s.rotary_inertia_y_t_mm = s.rotary_inertia_z_t_mm =
        s.mass_per_length_t_per_mm * radius * radius / 4.0;
    s.polar_inertia_t_mm = s.mass_per_length_t_per_mm * radius * radius / 2.0;
    if (std::isnan(s.bending_stiffness_y_Nmm2) || std::isnan(s.bending_stiffness_z_Nmm2))
        throw ModelError(path + ".EI_Nmm2: missing (or give EI_y_Nmm2 and EI_z_Nmm2)");
    // Range checks under the names the file uses.
    require_positive(s.bending_stiffness_y_Nmm2,
                     o.field(o.has("EI_y_Nmm2") ? "EI_y_Nmm2" : "EI_Nmm2"));
    require_positive(s.bending_stiffness_z_Nmm2,
                     o.field(o.has("EI_z_Nmm2") ? "EI_z_Nmm2" : "EI_Nmm2"));
    require_positive(s.axial_stiffness_N, o.field("EA_N"));
    require_positive(s.torsional_stiffness_Nmm2, o.field("GJ_Nmm2"));
    if (o.has("kappa_GA_N"))
        require_positive(s.shear_stiffness_y_N, o.field("kappa_GA_N"));  // absent: rigid in shear
    s.validate(path + ".");
    return s;
}

ScopeBeam read_beam(const JsonObject& o) {
    o.allow_only({"nodes_mm", "straight", "section"});
    const BeamSection section = read_section(o.raw("section"), o.field("section"));
    if (o.has("nodes_mm") == o.has("straight"))
        throw ModelError(o.path() + ": give exactly one of nodes_mm or straight");
    if (o.has("straight")) {
        const JsonObject st = o.object("straight");
        st.allow_only({"start_mm", "direction", "length_mm", "elements"});
        const double length = st.number("length_mm");
        require_positive(length, st.field("length_mm"));
        const std::size_t elements = st.index("elements");
        if (elements < 1 || elements > 100000)
            throw ModelError(st.field("elements") + ": must be in 1..100000");
        const Eigen::Vector3d direction = st.vector3_or("direction", Eigen::Vector3d::UnitX());
        if (!(direction.norm() > 0.0))
            throw ModelError(st.field("direction") + ": must not be the zero vector");
        return straight_beam(st.vector3_or("start_mm", Eigen::Vector3d::Zero()), direction, length,
                             elements, section);
    }
    const nlohmann::json& nodes = o.array("nodes_mm");
    std::vector<Eigen::Vector3d> points;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const std::string path = o.field("nodes_mm") + "[" + std::to_string(i) + "]";
        if (!nodes[i].is_array() || nodes[i].size() != 3)
            throw ModelError(path + ": expected [x, y, z] in mm");
        Eigen::Vector3d p;
        for (std::size_t c = 0; c < 3; ++c) {
            if (!nodes[i][c].is_number()) throw ModelError(path + ": expected numbers");
            p(static_cast<Eigen::Index>(c)) = nodes[i][c].get<double>();
        }
        points.push_back(p);
    }
    return ScopeBeam(std::move(points), {section});
}

Eigen::Matrix3d read_rotation(const JsonObject& o) {
    o.allow_only({"axis", "angle_deg"});
    const Eigen::Vector3d axis = o.vector3("axis");
    if (!(axis.norm() > 0.0)) throw ModelError(o.field("axis") + ": must not be the zero vector");
    return Eigen::AngleAxisd(o.number("angle_deg") * M_PI / 180.0, axis.normalized())
        .toRotationMatrix();
}

}  // namespace

BeamProblem read_beam_problem(const nlohmann::json& document, const std::string& source) {
    const JsonObject root(document, source + ":");
    root.allow_only({"description", "beam", "gravity_mm_per_s2", "loads", "supports", "static",
                     "output_nodes"});
    BeamProblem p{read_beam(root.object("beam")), {}, {}, {}, {}};
    p.loads.gravity_mm_per_s2 = root.vector3_or("gravity_mm_per_s2", Eigen::Vector3d::Zero());
    if (root.has("loads")) {
        const nlohmann::json& loads = root.array("loads");
        for (std::size_t i = 0; i < loads.size(); ++i) {
            const JsonObject l(loads[i], root.field("loads") + "[" + std::to_string(i) + "]");
            l.allow_only({"node", "force_N", "moment_Nmm"});
            p.loads.nodal.push_back({l.index("node"),
                                     l.vector3_or("force_N", Eigen::Vector3d::Zero()),
                                     l.vector3_or("moment_Nmm", Eigen::Vector3d::Zero())});
        }
    }
    const nlohmann::json& supports = root.array("supports");
    for (std::size_t i = 0; i < supports.size(); ++i) {
        const JsonObject s(supports[i], root.field("supports") + "[" + std::to_string(i) + "]");
        s.allow_only({"node", "fix_x", "fix_y", "fix_z", "fix_rotation", "target_position_mm",
                      "target_rotation"});
        NodeSupport support;
        support.node = s.index("node");
        support.fixed_translation = {s.boolean_or("fix_x", true), s.boolean_or("fix_y", true),
                                     s.boolean_or("fix_z", true)};
        support.fixed_rotation = s.boolean_or("fix_rotation", true);
        if (s.has("target_position_mm"))
            support.target_position_mm = s.vector3("target_position_mm");
        if (s.has("target_rotation"))
            support.target_rotation = read_rotation(s.object("target_rotation"));
        p.supports.push_back(support);
    }
    if (root.has("static")) {
        const JsonObject st = root.object("static");
        st.allow_only({"load_steps", "max_iterations", "relative_tolerance"});
        p.settings.load_steps = static_cast<int>(st.index_or("load_steps", 10));
        p.settings.max_iterations = static_cast<int>(st.index_or("max_iterations", 30));
        p.settings.relative_tolerance = st.number_or("relative_tolerance", 1e-9);
        if (p.settings.load_steps < 1 || p.settings.load_steps > 100000)
            throw ModelError(st.field("load_steps") + ": must be in 1..100000");
        if (p.settings.max_iterations < 1 || p.settings.max_iterations > 1000)
            throw ModelError(st.field("max_iterations") + ": must be in 1..1000");
        require_positive(p.settings.relative_tolerance, st.field("relative_tolerance"));
    }
    if (root.has("output_nodes")) {
        const nlohmann::json& nodes = root.array("output_nodes");
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            if (!nodes[i].is_number_integer() || nodes[i].get<long long>() < 0 ||
                static_cast<std::size_t>(nodes[i].get<long long>()) >= p.beam.node_count())
                throw ModelError(root.field("output_nodes") + "[" + std::to_string(i) +
                                 "]: not a node of the beam (0.." +
                                 std::to_string(p.beam.node_count() - 1) + ")");
            p.output_nodes.push_back(static_cast<std::size_t>(nodes[i].get<long long>()));
        }
    } else {
        for (std::size_t i = 0; i < p.beam.node_count(); ++i)
            p.output_nodes.push_back(i);
    }
    try {
        p.loads.assemble(p.beam);               // validates load node indices and values
        validate_supports(p.beam, p.supports);  // validates support node indices and targets
    } catch (const ModelError& error) {
        // Those checks name the field only (they also guard problems built in code): the file too.
        throw ModelError(source + ": " + error.what());
    }
    return p;
}

BeamProblem read_beam_problem_file(const std::string& filename) {
    return read_beam_problem(parse_json_file(filename), filename);
}

}  // namespace scopekin::model::io
