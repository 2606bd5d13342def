#include "host_sim/view/box_bus_rows.hpp"

#include "host_sim/simulator/live_simulation.hpp"

namespace scopekin::view {
namespace {

double q16(fixed_point::Q16_16 v) {
    return static_cast<double>(v.raw()) / 65536.0;
}

/// Decodes `frame` into `message` if it is that message: true if it was (decoded or refused).
template <typename Message>
bool take(const hal::CanFrame& frame, std::uint32_t id, Message& message, std::uint64_t& refused) {
    if (frame.id != id) return false;
    Message decoded{};
    if (protocol::decode(frame, decoded) == protocol::DecodeResult::ok) {
        message = decoded;
    } else {
        ++refused;
    }
    return true;
}

}  // namespace

void BoxBusRows::feed(std::uint64_t timestamp_us, const hal::CanFrame& frame) {
    if (!first_seen_) {
        first_seen_ = true;
        first_us_ = timestamp_us;
    }
    if (frame.error || frame.extended || frame.remote) {
        ++ignored_;
        return;
    }
    if (frame.id == protocol::kKineticEstimateId) {
        protocol::KineticEstimate decoded{};
        if (protocol::decode(frame, decoded) != protocol::DecodeResult::ok) {
            ++refused_;
            return;
        }
        flush();
        estimate_ = decoded;
        open_ = true;
        period_s_ = static_cast<double>(timestamp_us - first_us_) * 1e-6;
        return;
    }
    protocol::StationForces station{};
    if (take(frame, protocol::kStationForcesId, station, refused_)) {
        if (station.station < stations_.size())
            stations_[station.station] = {true, station.path_mm, station.normal_force_N};
        return;
    }
    protocol::BoxStatus status{};
    if (take(frame, protocol::kBoxStatusId, status, refused_)) {
        kinetic_faults_ = status.kinetic_faults;
        return;
    }
    protocol::BoxCounter counter{};
    protocol::EstimateEvidence evidence{};
    if (take(frame, protocol::kHandleForceTorqueId, handle_, refused_) ||
        take(frame, protocol::kInsertionRollId, insertion_, refused_) ||
        take(frame, protocol::kContactSummaryId, summary_, refused_) ||
        take(frame, protocol::kAlarmsId, alarms_, refused_) ||
        take(frame, protocol::kBoxCountersId, counter, refused_) ||
        take(frame, protocol::kEstimateEvidenceId, evidence, refused_))
        return;
    ++ignored_;
}

void BoxBusRows::flush() {
    if (!open_) return;
    open_ = false;
    ++periods_;
    on_row_(period_s_, row());
}

nlohmann::ordered_json BoxBusRows::row() const {
    // The same row as `run --view`'s (host_sim::box_view_row), from what the bus carried: the
    // stations heard so far in index order.
    kinetics::Outputs box{};
    box.tip_path_mm = estimate_.tip_path_mm;
    box.tip_uncertainty_mm = estimate_.tip_uncertainty_mm;
    box.max_contact_force_N = summary_.max_contact_force_N;
    box.self_lock_alarm = alarms_.self_lock;
    box.contact_force_level = static_cast<kinetics::ContactForceLevel>(alarms_.contact_force_level);
    box.fault_flags = kinetic_faults_;
    std::uint8_t heard = 0;
    for (std::size_t k = 0; k < summary_.active_stations && k < stations_.size(); ++k) {
        if (!stations_[k].heard || heard >= box.stations.size()) continue;
        box.stations[heard].path_position_mm = stations_[k].path_mm;
        box.stations[heard].normal_force_N = stations_[k].normal_N;
        ++heard;
    }
    box.active_stations = heard;
    return host_sim::box_view_row(
        period_s_, {q16(handle_.force_N), q16(handle_.torque_Nmm), q16(insertion_.insertion_mm)},
        box);
}

}  // namespace scopekin::view
