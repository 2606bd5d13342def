#pragma once
// Watches the box period by period: writes firmware.csv, and keeps what a summary needs — the
// alarm timeline (raised / cleared times of each alarm), the peak estimated contact force and
// where, and how many periods carried each fault flag: the estimator's (kinetics FaultFlag) and
// the box's own (messages::BoxFault, TrackerFault: its drivers, CAN controller and schedule),
// with the box's counters at the end (box_section(): summary.json "box").
#include <array>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hal/can_bus.hpp"
#include "host_sim/simulator/firmware_loop.hpp"

namespace scopekin::host_sim {

/// One alarm episode. Kinds: "self_lock", "contact_force_warning" (level warning or above),
/// "contact_force_critical".
struct AlarmEpisode {
    std::string kind;
    double raised_s = 0;
    std::optional<double> cleared_s;
    double tip_path_mm = 0;  ///< the estimated tip position when raised
};

struct BoxObservation {
    std::uint64_t periods = 0;
    std::vector<AlarmEpisode> alarms;
    double peak_contact_force_N = 0;  ///< estimated, largest station force
    double peak_contact_time_s = 0;
    double peak_contact_path_mm = 0;
    unsigned peak_contact_station = 0;
    std::array<std::uint64_t, 15> fault_periods{};  ///< periods with kinetics fault bit k set
    std::array<double, 15> fault_first_s{};         ///< time of the first such period [s] (if any)
    std::uint64_t estimate_invalid_periods = 0;
    std::array<std::uint64_t, 16> box_fault_periods{};  ///< periods with BoxFault bit k set
    std::array<double, 16> box_fault_first_s{};
    std::array<std::uint64_t, 8> tracker_fault_periods{};  ///< periods with TrackerFault bit k
    std::array<double, 8> tracker_fault_first_s{};
    /// The box's counters after the last period (known only when the periods carry the box).
    bool box_known = false;
    executive::BoxCounters box_counters{};
    drivers::HandleSensorCounters handle_counters{};
    drivers::EmTrackerDriverCounters em_counters{};
    hal::CanCounters can_counters{};
    std::uint32_t can_error_frames = 0, can_bus_off_events = 0, can_recoveries = 0;
    std::uint8_t box_state = 0;  ///< protocol::BoxState of the last period
};

/// Names of the kinetics fault bits (kinetics_io.hpp FaultFlag), bit k.
const std::array<const char*, 15>& kinetics_fault_names();
/// Names of the box's fault bits (messages/box_faults.hpp BoxFault, TrackerFault), bit k
/// ("bit_15" for a bit without a name).
const std::array<const char*, 16>& box_fault_names();
const std::array<const char*, 8>& tracker_fault_names();

class BoxObserver {
public:
    /// `csv` (may be null): firmware.csv is written there, header first.
    explicit BoxObserver(std::ostream* csv);
    void observe(const BoxPeriod& period);
    const BoxObservation& observation() const { return observation_; }
    /// The observation as JSON (alarms, peak, fault periods by name).
    nlohmann::ordered_json to_json() const;
    /// The box's own faults and counters as JSON (summary.json "box"): fault_periods and
    /// fault_first_s by BoxFault name, tracker_fault_periods and tracker_fault_first_s, the
    /// counters of the executive, the handle sensors (counter_gaps ...), the EM tracker and the
    /// CAN bus.
    nlohmann::ordered_json box_section() const;

private:
    void edge(const char* kind, bool now, bool& before, double time_s, double tip_mm);
    std::ostream* csv_;
    BoxObservation observation_;
    bool self_lock_ = false, warning_ = false, critical_ = false;
};

}  // namespace scopekin::host_sim
