#include "host_sim/simulator/world_csv.hpp"

#include <cmath>
#include <cstdio>

namespace scopekin::host_sim {
namespace {

std::string num(double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.7g", v);
    return buffer;
}

}  // namespace

std::string world_csv_header(const model::Scenario& sc, const std::vector<std::size_t>& nodes) {
    std::string h =
        "time_s,handle_force_N,handle_torque_Nmm,insertion_depth_mm,roll_deg,tip_x_mm,tip_y_mm,tip_"
        "z_mm";
    for (std::size_t node : nodes) {
        const double arc = sc.scope.length_mm * static_cast<double>(sc.scope.elements - node) /
                           static_cast<double>(sc.scope.elements);
        char label[32];
        std::snprintf(label, sizeof label, "%g", arc);
        const std::string base = "node_" + std::string(label) + "mm_";
        h += "," + base + "x_mm," + base + "y_mm," + base + "z_mm";
    }
    h += ",contact_count,contact_force_total_N,contact_force_max_N";
    for (model::ColonRegion r : model::kColonRegionsInOrder)
        h += ",max_contact_force_" + std::string(model::region_name(r)) + "_N";
    h += ",sticking_contacts,slipping_contacts,tip_driving_angle_deg,gs_sweeps,tip_path_mm,tip_"
         "contact_force_N,tip_region,assistant_pressure_force_N";
    return h;
}

void write_world_csv_row(std::ostream& out, const model::WorldRow& s, const WorldReadout& r) {
    out << num(s.time_s) << ',' << num(s.handle_force_N) << ',' << num(s.handle_torque_Nmm) << ','
        << num(s.insertion_depth_mm) << ',' << num(s.roll_deg) << ',' << num(s.tip_mm.x()) << ','
        << num(s.tip_mm.y()) << ',' << num(s.tip_mm.z());
    for (const Eigen::Vector3d& p : s.nodes_mm)
        out << ',' << num(p.x()) << ',' << num(p.y()) << ',' << num(p.z());
    out << ',' << s.contact_count << ',' << num(s.contact_force_total_N) << ','
        << num(s.contact_force_max_N);
    for (double f : s.max_contact_force_by_region_N)
        out << ',' << num(f);
    out << ',' << s.sticking_contacts << ',' << s.slipping_contacts << ','
        << (s.has_tip_driving_angle ? num(s.tip_driving_angle_deg) : std::string()) << ','
        << s.gs_sweeps << ',' << num(r.tip_path_mm) << ',' << num(r.tip_force_N.norm()) << ','
        << r.tip_region << ',' << num(s.assistant_pressure_force_N) << '\n';
}

std::string contacts_csv_header() {
    return "time_s,scope_node,arc_from_tip_mm,region,x_mm,y_mm,z_mm,normal_force_N,tangential_"
           "force_N,"
           "friction_coefficient,driving_angle_deg,state,gap_mm";
}

void write_contacts_csv_rows(std::ostream& out, double time_s, const model::World& world) {
    for (const model::WorldContact& c : world.contacts()) {
        if (!(c.normal_force_N > 0.0)) continue;
        const char* state = c.state == contact::ContactState::sticking   ? "sticking"
                            : c.state == contact::ContactState::slipping ? "slipping"
                                                                         : "separated";
        out << num(time_s) << ',' << c.scope_node << ',' << num(c.arc_from_tip_mm) << ','
            << model::region_name(c.region) << ',' << num(c.scope_point_mm.x()) << ','
            << num(c.scope_point_mm.y()) << ',' << num(c.scope_point_mm.z()) << ','
            << num(c.normal_force_N) << ',' << num(c.tangential_force_N) << ','
            << num(c.friction_coefficient) << ',' << num(c.driving_angle_rad * 180.0 / M_PI) << ','
            << state << ',' << num(c.gap_mm) << '\n';
    }
}

std::string procedure_csv_header() {
    return "time_s,state,speed_mm_per_s,roll_deg,steering,pressure";
}

void write_procedure_csv_row(std::ostream& out, double time_s, const model::HandState& hand) {
    out << num(time_s) << ',' << hand.state << ',' << num(hand.speed_mm_per_s) << ','
        << num(hand.roll_deg) << ',' << (hand.steering ? 1 : 0) << ',' << (hand.pressure ? 1 : 0)
        << '\n';
}

}  // namespace scopekin::host_sim
