#include "host_sim/simulator/box_observer.hpp"

#include <utility>

#include "host_sim/simulator/firmware_csv.hpp"

namespace scopekin::host_sim {

const std::array<const char*, 15>& kinetics_fault_names() {
    static const std::array<const char*, 15> names{
        "insertion_stale", "insertion_range",  "insertion_jump", "force_stale",
        "force_range",     "torque_stale",     "torque_range",   "roll_stale",
        "roll_range",      "contact_residual", "saturation",     "depth_outside_model",
        "config",          "monitor_input",    "force_blind"};
    return names;
}

const std::array<const char*, 16>& box_fault_names() {
    // messages::BoxFault, bit k (BoxStatus.DriverFaults).
    static const std::array<const char*, 16> names{"force_torque_stale",
                                                   "encoder_stale",
                                                   "bad_length",
                                                   "unknown_id",
                                                   "out_of_range",
                                                   "sensor_status",
                                                   "counter_gap",
                                                   "can_error_frame",
                                                   "bus_off",
                                                   "receive_dropped",
                                                   "send_failed",
                                                   "serial_framing",
                                                   "tracker_stale",
                                                   "period_overrun",
                                                   "receive_backlog",
                                                   "bit_15"};
    static_assert(messages::kBoxFaultCounterGap == 1U << 6U);
    static_assert(messages::kBoxFaultPeriodOverrun == 1U << 13U);
    static_assert(messages::kBoxFaultReceiveBacklog == 1U << 14U);
    return names;
}

const std::array<const char*, 8>& tracker_fault_names() {
    // messages::TrackerFault, bit k (BoxStatus.TrackerFaults).
    static const std::array<const char*, 8> names{
        "stale",          "out_of_range",  "quaternion_norm", "device_time",
        "unknown_sensor", "device_status", "framing",         "link"};
    static_assert(messages::kTrackerFaultLink == 1U << 7U);
    return names;
}

BoxObserver::BoxObserver(std::ostream* csv) : csv_(csv) {
    if (csv_ != nullptr) *csv_ << firmware_csv_header() << '\n';
}

void BoxObserver::edge(const char* kind, bool now, bool& before, double time_s, double tip_mm) {
    if (now && !before) observation_.alarms.push_back({kind, time_s, std::nullopt, tip_mm});
    if (!now && before) {
        for (auto it = observation_.alarms.rbegin(); it != observation_.alarms.rend(); ++it)
            if (it->kind == kind && !it->cleared_s) {
                it->cleared_s = time_s;
                break;
            }
    }
    before = now;
}

void BoxObserver::observe(const BoxPeriod& period) {
    const kinetics::Outputs& o = *period.outputs;
    const std::uint8_t tracker_faults = period.box != nullptr ? period.box->tracker_faults() : 0U;
    if (csv_ != nullptr)
        *csv_ << firmware_csv_row(period.time_us, o, period.box_faults, tracker_faults) << '\n';
    ++observation_.periods;
    const double t = static_cast<double>(period.time_us) * 1e-6;
    // The box's fault times as firmware.csv prints time_s (the double nearest the microseconds:
    // a candump log's epoch times stay exact in summary.json).
    const double t_us_exact = static_cast<double>(period.time_us) / 1e6;
    for (std::size_t k = 0; k < observation_.box_fault_periods.size(); ++k)
        if ((period.box_faults & (1U << k)) != 0U && observation_.box_fault_periods[k]++ == 0)
            observation_.box_fault_first_s[k] = t_us_exact;
    for (std::size_t k = 0; k < observation_.tracker_fault_periods.size(); ++k)
        if ((tracker_faults & (1U << k)) != 0U && observation_.tracker_fault_periods[k]++ == 0)
            observation_.tracker_fault_first_s[k] = t_us_exact;
    if (period.box != nullptr) {
        const executive::SensorBox& box = *period.box;
        observation_.box_known = true;
        observation_.box_counters = box.counters();
        observation_.handle_counters = box.handle_sensors().counters();
        observation_.em_counters = box.em_tracker().counters();
        observation_.can_counters = box.can_counters();
        observation_.can_error_frames = box.can_health().error_frames();
        observation_.can_bus_off_events = box.can_health().bus_off_events();
        observation_.can_recoveries = box.can_health().recoveries();
        observation_.box_state = static_cast<std::uint8_t>(box.box_state());
    }
    const double tip = static_cast<double>(o.tip_path_mm.raw()) / 65536.0;
    edge("self_lock", o.self_lock_alarm, self_lock_, t, tip);
    edge("contact_force_warning", o.contact_force_level != kinetics::ContactForceLevel::normal,
         warning_, t, tip);
    edge("contact_force_critical", o.contact_force_level == kinetics::ContactForceLevel::critical,
         critical_, t, tip);
    const double peak = static_cast<double>(o.max_contact_force_N.raw()) / 65536.0;
    if (peak > observation_.peak_contact_force_N) {
        observation_.peak_contact_force_N = peak;
        observation_.peak_contact_time_s = t;
        observation_.peak_contact_path_mm =
            static_cast<double>(o.max_contact_path_mm.raw()) / 65536.0;
        observation_.peak_contact_station = o.max_contact_station;
    }
    for (std::size_t k = 0; k < observation_.fault_periods.size(); ++k)
        if ((o.fault_flags & (1U << k)) != 0U && observation_.fault_periods[k]++ == 0)
            observation_.fault_first_s[k] = t;
    if ((o.fault_flags & kinetics::kFaultConfig) != 0U) ++observation_.estimate_invalid_periods;
}

nlohmann::ordered_json BoxObserver::to_json() const {
    using Json = nlohmann::ordered_json;
    Json alarms = Json::array();
    for (const AlarmEpisode& a : observation_.alarms)
        alarms.push_back({{"kind", a.kind},
                          {"raised_s", a.raised_s},
                          {"cleared_s", a.cleared_s ? Json(*a.cleared_s) : Json(nullptr)},
                          {"estimated_tip_path_mm", a.tip_path_mm}});
    Json faults = Json::object();
    for (std::size_t k = 0; k < observation_.fault_periods.size(); ++k)
        faults[kinetics_fault_names()[k]] = observation_.fault_periods[k];
    Json out;
    out["periods"] = observation_.periods;
    out["alarms"] = alarms;
    out["peak_estimated_contact_force"] = {{"force_N", observation_.peak_contact_force_N},
                                           {"time_s", observation_.peak_contact_time_s},
                                           {"path_mm", observation_.peak_contact_path_mm},
                                           {"station", observation_.peak_contact_station}};
    out["fault_periods"] = faults;
    Json first = Json::object();
    for (std::size_t k = 0; k < observation_.fault_periods.size(); ++k)
        if (observation_.fault_periods[k] > 0)
            first[kinetics_fault_names()[k]] = observation_.fault_first_s[k];
    out["fault_first_s"] = first;
    return out;
}

nlohmann::ordered_json BoxObserver::box_section() const {
    using Json = nlohmann::ordered_json;
    const BoxObservation& b = observation_;
    auto by_name = [](const auto& names, const auto& periods, const auto& first_s) {
        Json counts = Json::object(), first = Json::object();
        for (std::size_t k = 0; k < periods.size(); ++k) {
            counts[names[k]] = periods[k];
            if (periods[k] > 0) first[names[k]] = first_s[k];
        }
        return std::pair<Json, Json>{counts, first};
    };
    const auto [box_periods, box_first] =
        by_name(box_fault_names(), b.box_fault_periods, b.box_fault_first_s);
    const auto [tracker_periods, tracker_first] =
        by_name(tracker_fault_names(), b.tracker_fault_periods, b.tracker_fault_first_s);
    Json out;
    out["periods"] = b.periods;
    out["fault_periods"] = box_periods;
    out["fault_first_s"] = box_first;
    out["tracker_fault_periods"] = tracker_periods;
    out["tracker_fault_first_s"] = tracker_first;
    if (!b.box_known) return out;
    static constexpr std::array<const char*, 4> kStates{"starting", "running", "degraded",
                                                        "no_estimate"};
    out["state_at_end"] = b.box_state < kStates.size() ? kStates[b.box_state] : "unknown";
    const executive::BoxCounters& c = b.box_counters;
    out["counters"] = {{"periods", c.periods},
                       {"frames_read", c.frames_read},
                       {"unknown_ids", c.unknown_ids},
                       {"frames_published", c.frames_published},
                       {"send_failures", c.send_failures},
                       {"period_overruns", c.period_overruns},
                       {"backlog_periods", c.backlog_periods},
                       {"late_frames", c.late_frames}};
    const drivers::HandleSensorCounters& h = b.handle_counters;
    out["handle_sensors"] = {{"force_torque_samples", h.force_torque_samples},
                             {"insertion_roll_samples", h.insertion_roll_samples},
                             {"bad_length", h.bad_length},
                             {"out_of_range", h.out_of_range},
                             {"sensor_status", h.sensor_status},
                             {"counter_gaps", h.counter_gaps},
                             {"stale_events", h.stale_events},
                             {"late_samples", h.late_samples}};
    const drivers::EmTrackerDriverCounters& e = b.em_counters;
    out["em_tracker"] = {{"poses_ok", e.poses_ok},
                         {"tip_forces_ok", e.tip_forces_ok},
                         {"unknown_sensor", e.unknown_sensor},
                         {"out_of_range", e.out_of_range},
                         {"quaternion_norm", e.quaternion_norm},
                         {"timestamp_backwards", e.timestamp_backwards},
                         {"device_status", e.device_status},
                         {"stale_events", e.stale_events},
                         {"samples_dropped", e.samples_dropped},
                         {"malformed_payload", e.malformed_payload},
                         {"serial_closed", e.serial_closed},
                         {"serial_errors", e.serial_errors},
                         {"frames_ok", e.link.frames_ok},
                         {"bad_checksum", e.link.bad_checksum},
                         {"bad_length", e.link.bad_length},
                         {"unknown_type", e.link.unknown_type},
                         {"bytes_discarded", e.link.bytes_discarded},
                         {"buffer_overflows", e.link.buffer_overflows}};
    const hal::CanCounters& can = b.can_counters;
    out["can"] = {{"received", can.received},
                  {"sent", can.sent},
                  {"send_failures", can.send_failures},
                  {"error_frames", can.error_frames},
                  {"dropped", can.dropped},
                  {"bus_off_events", can.bus_off_events},
                  {"backend_errors", can.backend_errors},
                  {"controller_error_frames", b.can_error_frames},
                  {"controller_bus_off_events", b.can_bus_off_events},
                  {"controller_recoveries", b.can_recoveries}};
    return out;
}

}  // namespace scopekin::host_sim
