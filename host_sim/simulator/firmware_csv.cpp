#include "host_sim/simulator/firmware_csv.hpp"

#include <cinttypes>
#include <cstdio>

namespace scopekin::host_sim {
namespace {

void put_q(std::string& line, fixed_point::Q16_16 q) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, ",%.5f", static_cast<double>(q.raw()) / 65536.0);
    line += buffer;
}

void put_u(std::string& line, std::uint64_t v) {
    line += ',';
    line += std::to_string(v);
}

}  // namespace

std::string firmware_csv_header() {
    std::string h =
        "time_s,step_index,tip_path_mm,tip_velocity_mm_per_s,advance_efficiency,active_stations,"
        "max_contact_force_N,"
        "max_contact_station,max_contact_path_mm,distal_sticking,self_lock_alarm,contact_force_"
        "level,fault_flags";
    for (std::size_t k = 0; k < kinetics::kStationCapacity; ++k) {
        const std::string s = "station_" + std::to_string(k) + "_";
        h += "," + s + "arc_mm," + s + "path_mm," + s + "normal_N," + s + "tangential_N," + s +
             "state";
    }
    return h +
           ",box_faults,tracker_faults,tip_uncertainty_mm,model_tip_path_mm,"
           "model_log_likelihood_ratio,tip_from_model,observer_tip_path_mm,"
           "max_contact_force_uncertainty_N,model_max_contact_force_N,model_self_lock_alarm,"
           "loop_score,tip_from_tracker,model_contact_force_level";
}

std::string firmware_csv_row(std::uint64_t time_us, const kinetics::Outputs& o,
                             std::uint16_t box_faults, std::uint8_t tracker_faults) {
    char time[32];
    std::snprintf(time, sizeof time, "%" PRIu64 ".%06" PRIu64, time_us / 1000000U,
                  time_us % 1000000U);
    std::string line = time;
    put_u(line, o.step_index);
    put_q(line, o.tip_path_mm);
    put_q(line, o.tip_velocity_mm_per_s);
    put_q(line, o.advance_efficiency);
    put_u(line, o.active_stations);
    put_q(line, o.max_contact_force_N);
    put_u(line, o.max_contact_station);
    put_q(line, o.max_contact_path_mm);
    put_u(line, o.distal_sticking);
    put_u(line, o.self_lock_alarm ? 1U : 0U);
    put_u(line, static_cast<std::uint64_t>(o.contact_force_level));
    put_u(line, o.fault_flags);
    for (const kinetics::StationEstimate& s : o.stations) {
        put_q(line, s.arc_from_tip_mm);
        put_q(line, s.path_position_mm);
        put_q(line, s.normal_force_N);
        put_q(line, s.tangential_force_N);
        put_u(line, static_cast<std::uint64_t>(s.state));
    }
    put_u(line, box_faults);
    put_u(line, tracker_faults);
    put_q(line, o.tip_uncertainty_mm);
    put_q(line, o.model_tip_path_mm);
    put_q(line, o.model_log_likelihood_ratio);
    put_u(line, o.tip_from_model ? 1U : 0U);
    put_q(line, o.observer_tip_path_mm);
    put_q(line, o.max_contact_force_uncertainty_N);
    put_q(line, o.model_max_contact_force_N);
    put_u(line, o.model_self_lock_alarm ? 1U : 0U);
    put_q(line, o.loop_score);
    put_u(line, o.tip_from_tracker ? 1U : 0U);
    put_u(line, static_cast<std::uint64_t>(o.model_contact_force_level));
    return line;
}

}  // namespace scopekin::host_sim
