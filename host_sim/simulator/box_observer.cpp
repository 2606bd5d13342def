#include "host_sim/simulator/box_observer.hpp"

#include "host_sim/simulator/firmware_csv.hpp"

namespace scopekin::host_sim {

const std::array<const char*, 14>& kinetics_fault_names() {
    static const std::array<const char*, 14> names{
        "insertion_stale", "insertion_range",  "insertion_jump", "force_stale",
        "force_range",     "torque_stale",     "torque_range",   "roll_stale",
        "roll_range",      "contact_residual", "saturation",     "depth_outside_model",
        "config",          "monitor_input"};
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
    if (csv_ != nullptr) *csv_ << firmware_csv_row(period.time_us, o) << '\n';
    ++observation_.periods;
    const double t = static_cast<double>(period.time_us) * 1e-6;
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

}  // namespace scopekin::host_sim
